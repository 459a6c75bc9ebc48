"""What each difficulty draws its layouts from."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Ranges:
    """What a difficulty draws from: (low, high) ranges, uniform; counts inclusive."""

    width: tuple[float, float]  # playfield width, shooter lane included [m]
    aspect: tuple[float, float]  # height / width
    slope: tuple[float, float]  # [deg]
    flipper_length: tuple[float, float]  # pivot to tip centre [m]
    flipper_gap: tuple[float, float]  # between the flipper tips at rest, surface to surface [m]
    rest_angle: tuple[float, float]  # below horizontal [deg]
    swing: tuple[float, float]  # [deg]
    outlane: tuple[float, float]  # outlane width [m]
    upper_deflectors: float  # chance of a right upper deflector (the left is always there)
    slingshot_kick: tuple[float, float]  # [m/s]
    bumpers: tuple[int, int]
    posts: tuple[int, int]
    deflectors: tuple[int, int]
    top_lanes: tuple[int, ...]  # lane counts to choose from (0: none)


RANGES = {
    "easy": Ranges(
        width=(0.46, 0.60), aspect=(1.85, 2.2), slope=(6.0, 6.75), flipper_length=(0.066, 0.08),
        flipper_gap=(0.034, 0.042), rest_angle=(22.0, 28.0), swing=(48.0, 55.0),
        outlane=(0.035, 0.040), upper_deflectors=0.8, slingshot_kick=(1.0, 1.3), bumpers=(2, 5),
        posts=(0, 2), deflectors=(0, 1), top_lanes=(0, 2, 3),
    ),
    "hard": Ranges(
        width=(0.46, 0.60), aspect=(1.85, 2.2), slope=(6.5, 7.5), flipper_length=(0.056, 0.07),
        flipper_gap=(0.042, 0.052), rest_angle=(25.0, 32.0), swing=(45.0, 52.0),
        outlane=(0.038, 0.048), upper_deflectors=0.3, slingshot_kick=(1.2, 1.6), bumpers=(1, 4),
        posts=(0, 3), deflectors=(0, 3), top_lanes=(0, 2, 3, 4),
    ),
}  # fmt: skip
