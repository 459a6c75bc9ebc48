"""The colours of rendered tables and their grayscale (BT.601 luma, in exact integers)."""

from collections.abc import Sequence

import numpy as np

Colour = Sequence[int] | np.ndarray  # (R, G, B), or (luma,) for the grayscale layer

# Colours (R, G, B). Chosen so that in grayscale the ball is the brightest thing and the flippers
# stand well clear of the background.
BACKGROUND = (16, 20, 32)
WALL = (165, 180, 205)
ONE_SIDED = (240, 135, 45)
KICKER = (225, 55, 65)
POST = (40, 155, 140)
SENSOR = (62, 72, 92)
DRAIN = (92, 52, 62)
FLIPPER = (250, 195, 60)
BALL = (248, 248, 252)
PLUNGER = (190, 195, 210)  # the player's plunger: steel, darker than the ball in grayscale
# Targets and rules: standing drop targets and stand-ups, fallen ones, spinner flaps, lit and dark
# lamps (the rules' lights, a lit kickback).
TARGET = (120, 170, 250)
TARGET_DOWN = (44, 52, 78)
SPINNER = (200, 205, 220)
LIGHT_ON = (255, 240, 120)
LIGHT_OFF = (70, 62, 40)
SCOREBOARD_TEXT = (250, 195, 60)
SCOREBOARD_ALERT = (235, 60, 50)  # the scoreboard's tilt warnings and TILT

# ITU-R BT.601 luma weights (as PIL's "L" mode and OpenCV use), in thousandths so that the
# grayscale image is computed in exact integer arithmetic.
LUMA_WEIGHTS = (299, 587, 114)


def luminance(colour: Colour) -> np.ndarray:
    """BT.601 luma of uint8 RGB values (last axis), rounded, as uint8 with that axis kept as 1."""
    rgb = np.asarray(colour, dtype=np.uint32)
    luma = (rgb * np.array(LUMA_WEIGHTS, dtype=np.uint32)).sum(axis=-1, keepdims=True)
    return ((luma + 500) // 1000).astype(np.uint8)


def rgb(colour: Colour) -> np.ndarray:
    """``colour`` as a uint8 array, as the painters take it."""
    return np.asarray(colour, dtype=np.uint8)
