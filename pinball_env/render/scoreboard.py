"""The scoreboard beside rendered frames: the score and the balls left, in a 3x5 pixel font; on a
table with the cabinet its tilt warnings and TILT, on one with rules the bonus and its
multiplier."""

import numpy as np

from pinball_env.render.colours import BACKGROUND, SCOREBOARD_ALERT, SCOREBOARD_TEXT, Colour

SCOREBOARD_WIDTH = 110  # [px]
# A 3x5 pixel font (rows top to bottom, bits left to right) for the characters the scoreboard
# shows, drawn in solid blocks.
_FONT = {
    "0": (7, 5, 5, 5, 7), "1": (2, 6, 2, 2, 7), "2": (7, 1, 7, 4, 7), "3": (7, 1, 7, 1, 7),
    "4": (5, 5, 7, 1, 1), "5": (7, 4, 7, 1, 7), "6": (7, 4, 7, 5, 7), "7": (7, 1, 1, 1, 1),
    "8": (7, 5, 7, 5, 7), "9": (7, 5, 7, 1, 7), "A": (2, 5, 7, 5, 5), "B": (6, 5, 6, 5, 6),
    "C": (7, 4, 4, 4, 7), "E": (7, 4, 7, 4, 7), "G": (7, 4, 5, 5, 7), "I": (7, 2, 2, 2, 7),
    "L": (4, 4, 4, 4, 7), "N": (6, 5, 5, 5, 5), "O": (7, 5, 5, 5, 7), "R": (6, 5, 6, 5, 5),
    "S": (7, 4, 7, 1, 7), "T": (7, 2, 2, 2, 2), "W": (5, 5, 7, 7, 5), "/": (1, 1, 2, 4, 4),
    "U": (5, 5, 5, 5, 7), "X": (5, 5, 2, 5, 5), "H": (5, 5, 7, 5, 5),
    " ": (0, 0, 0, 0, 0),
}  # fmt: skip


def text_mask(text: str, scale: int) -> np.ndarray:
    """(5 scale, 4 scale len(text)) bool pixels of ``text`` in the scoreboard font (digits, "/"
    and the letters of SCORE, BALLS, WARNING, TILT and BONUS, X), each font pixel a ``scale`` x
    ``scale`` block."""
    rows = []
    for row in range(5):
        bits = []
        for char in text:
            code = _FONT[char][row]
            bits.extend([bool(code & 4), bool(code & 2), bool(code & 1), False])
        rows.append(bits)
    return np.kron(np.array(rows, dtype=np.uint8), np.ones((scale, scale), np.uint8)) > 0


def scoreboard(
    height: int,
    score: int,
    balls_left: int,
    width: int = SCOREBOARD_WIDTH,
    *,
    tilt_warnings: int = 0,
    allowed_warnings: int = 0,
    tilted: bool = False,
    bonus: int | None = None,
    multiplier: int = 1,
    trough: int | None = None,
) -> np.ndarray:
    """A (height, width, 3) uint8 strip showing the score and the balls left, as a machine's
    display does beside the playfield; below them, on a table with the cabinet, ``TILT`` while
    ``tilted``, else ``WARNING`` and ``tilt_warnings``/``allowed_warnings`` while a warning
    stands (nothing when none does, so that a table without a cabinet is drawn as before); on a
    table with rules (``bonus`` given) ``BONUS``, the bonus and ``X`` the multiplier; on a table
    of several balls (``trough`` given) ``TROUGH`` and the balls waiting in it."""
    strip = np.empty((height, width, 3), dtype=np.uint8)
    strip[...] = BACKGROUND
    sections: list[tuple[str, str | None, Colour]] = [
        ("SCORE", str(int(score)), SCOREBOARD_TEXT),
        ("BALLS", str(int(balls_left)), SCOREBOARD_TEXT),
    ]
    if trough is not None:
        sections.append(("TROUGH", str(int(trough)), SCOREBOARD_TEXT))
    if bonus is not None:
        sections.append(("BONUS", f"{int(bonus)} X{int(multiplier)}", SCOREBOARD_TEXT))
    if tilted:
        sections.append(("TILT", None, SCOREBOARD_ALERT))
    elif tilt_warnings > 0:
        sections.append(
            ("WARNING", f"{int(tilt_warnings)}/{int(allowed_warnings)}", SCOREBOARD_ALERT)
        )
    top = 10
    for label, value, colour in sections:
        for text, most in ((label, 4), (value, 4)):
            if text is None:
                continue
            scale = max(1, min(most, (width - 10) // (4 * len(text))))
            mask = text_mask(text, scale)
            rows, cols = min(mask.shape[0], max(height - top, 0)), min(mask.shape[1], width - 5)
            strip[top : top + rows, 5 : 5 + cols][mask[:rows, :cols]] = colour
            top += mask.shape[0] + 2 * scale
        top += 12
    return strip
