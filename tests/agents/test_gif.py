import numpy as np
import pytest

from agents.gif import GifWriter

iio = pytest.importorskip("imageio.v3")


def test_a_gif_holds_every_frame_on_one_palette_looping(tmp_path):
    """Frames of a few flat colours (as the render's) come back exactly, however little of a
    frame changes (one that changes nothing keeps its place and time), with their duration and
    an endless loop."""
    rng = np.random.default_rng(0)
    colours = np.array([[16, 20, 32], [250, 195, 60], [235, 60, 50], [165, 180, 205]], np.uint8)
    frames = [colours[rng.integers(0, 4, size=(40, 30))]]
    for k in range(12):
        frame = frames[-1].copy()
        if k % 4 != 3:  # every fourth frame the same as the one before
            frame[k : k + 3, 2 * k : 2 * k + 5] = colours[k % 4]
        frames.append(frame)
    path = tmp_path / "game.gif"
    with GifWriter(path, duration_ms=50) as gif:
        for frame in frames:
            gif.append_data(frame)
    read = iio.imread(path, index=None)
    assert read.shape == (len(frames), 40, 30, 3)
    assert all(np.array_equal(got, want) for got, want in zip(read, frames, strict=True))
    meta = iio.immeta(path)
    assert meta["duration"] == 50 and meta["loop"] == 0
