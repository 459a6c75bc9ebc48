"""A streaming GIF writer for whole games: frames are written as they come (a game of thousands
of frames never sits in memory), each mapped onto one palette taken from the first frame
(the table's colours) and cropped to what changed since the frame before. About 2 ms a frame
where imageio's writer, which builds a palette for every frame, takes about 20."""

from pathlib import Path

import numpy as np
from PIL import GifImagePlugin, Image

PALETTE_COLOURS = 64  # the render's flat colours fit; anti-aliased edges take the nearest


class GifWriter:
    """``with GifWriter(path, duration_ms) as gif: gif.append_data(frame)`` for each RGB
    frame (H, W, 3 uint8) of a looping GIF, ``duration_ms`` a frame."""

    def __init__(self, path: Path, duration_ms: float) -> None:
        self.path, self.duration = Path(path), round(duration_ms)
        self._file = self.path.open("wb")
        self._palette: Image.Image | None = None
        self._previous: np.ndarray | None = None

    def append_data(self, frame: np.ndarray) -> None:
        image = Image.fromarray(np.ascontiguousarray(frame[..., :3]))
        if self._palette is None:
            self._palette = image.quantize(PALETTE_COLOURS, Image.Quantize.MEDIANCUT)
        indices = np.asarray(image.quantize(palette=self._palette, dither=Image.Dither.NONE))
        if self._previous is None:
            header, _ = GifImagePlugin.getheader(self._palette, None, {"loop": 0})
            self._file.write(b"".join(header))
            left, top, right, bottom = 0, 0, indices.shape[1], indices.shape[0]
        else:  # only the box of what changed (at least a pixel: every frame keeps its time)
            changed = indices != self._previous
            rows, columns = np.flatnonzero(changed.any(axis=1)), np.flatnonzero(changed.any(axis=0))
            if len(rows) == 0:
                rows, columns = np.array([0]), np.array([0])
            left, top, right, bottom = columns[0], rows[0], columns[-1] + 1, rows[-1] + 1
        self._previous = indices
        box = np.ascontiguousarray(indices[top:bottom, left:right])
        part = Image.frombytes("P", (box.shape[1], box.shape[0]), box.tobytes())
        part.putpalette(self._palette.getpalette() or [])
        # (disposal 1: each frame drawn over the last, as the crop needs)
        for chunk in GifImagePlugin.getdata(part, (int(left), int(top)), duration=self.duration,
                                            disposal=1):  # fmt: skip
            self._file.write(chunk)

    def close(self) -> None:
        if not self._file.closed:
            self._file.write(b";")  # the trailer
            self._file.close()

    def __enter__(self) -> "GifWriter":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
