"""A table description with every multiball key: classic_v1's, with a saucer, a lock, a trough of
three balls (with its auto-plunger) and the ball-ball material. Shared by the table tests."""

import copy
from functools import cache
from typing import Any

from pinball_env.table import table_description


@cache
def _multiball() -> dict[str, Any]:
    data = table_description("classic_v1")  # a fresh copy, its base (classic) resolved
    data["name"] = "classic_v1_multiball"
    data["materials"]["steel"] = {"restitution": 0.95, "friction": 0.1}
    data["ball"]["material"] = "steel"
    data["saucers"] = [
        {
            "name": "right_saucer",
            "center": [0.40, 0.45],
            "radius": 0.02,
            "capture_speed": 0.5,
            "hold_time": 1.5,
            "kick": [-1.0, 1.5],
            "score": 500,
        }
    ]
    data["locks"] = [
        {
            "name": "left_lock",
            "slots": [[0.10, 0.45], [0.10, 0.48]],
            "capture_speed": 1.0,
            "kick": [0.5, -0.5],
            "score": 1000,
        }
    ]
    data["trough"] = {"balls": 3, "auto_plunger": {"speed": [2.5, 3.0]}}
    return data


def multiball_dict() -> dict[str, Any]:
    """A fresh copy of the description (the tests change theirs)."""
    return copy.deepcopy(_multiball())
