"""The buttons of the machine and the actions that press them, as ALE names its actions.

A table without a cabinet has the two flipper buttons (``BUTTONS``: left, right) and four
discrete actions, every combination of them. A table with the whole cabinet (the player's
plunger, the nudge and the tilt: ``Table.has_cabinet``) adds the plunger button and three
nudges (``CABINET_BUTTONS``), and 32 discrete actions: the four flipper combinations, with or
without the plunger, with no nudge or one of the three. Action ``a`` holds flippers ``a & 3``
(bit 0 left, bit 1 right), the plunger if bit 2 is set, and nudge ``a >> 3`` (0 none, 1 left,
2 right, 3 up), so the first four actions are the flipper-only ones of a table without a
cabinet. The ``MultiBinary`` form presses any set of buttons; nudges pressed together shove
the cabinet along the sum of their directions (left and right cancel). :func:`decode_actions`
turns a batch of actions into the buttons they hold.
"""

from typing import Any

import numpy as np

from pinball_env.table import BUTTONS

# The cabinet's buttons, after the flipper buttons in a buttons array.
CABINET_BUTTONS = ("plunger", "nudge_left", "nudge_right", "nudge_up")
# Direction of the shove of each nudge button, in the table frame (x right, y up the table).
NUDGE_DIRECTIONS = {"nudge_left": (-1.0, 0.0), "nudge_right": (1.0, 0.0), "nudge_up": (0.0, 1.0)}
_FLIPPER_NAMES = ("", "LEFT_FLIPPER", "RIGHT_FLIPPER", "BOTH_FLIPPERS")
_NUDGE_NAMES = ("", "NUDGE_LEFT", "NUDGE_RIGHT", "NUDGE_UP")


def button_names(cabinet: bool) -> tuple[str, ...]:
    """The columns of a buttons array: the flipper buttons, then the cabinet's if it has one."""
    return BUTTONS + CABINET_BUTTONS if cabinet else BUTTONS


def discrete_buttons(cabinet: bool, nudges: bool = True) -> np.ndarray:
    """(actions, buttons) bool, read-only: row ``a`` is the buttons discrete action ``a`` holds;
    without ``nudges``, a cabinet's first 8 actions, those that nudge left out."""
    n_actions = (32 if nudges else 8) if cabinet else 4
    rows = np.zeros((n_actions, len(button_names(cabinet))), dtype=bool)
    for action in range(n_actions):
        rows[action, 0] = action & 1
        rows[action, 1] = action >> 1 & 1
        if cabinet:
            rows[action, 2] = action >> 2 & 1
            nudge = action >> 3
            if nudge:
                rows[action, 2 + nudge] = True
    rows.flags.writeable = False
    return rows


# A discrete action of a table without a cabinet is the flipper buttons held as bits: bit i is
# button BUTTONS[i] (0 none, 1 left, 2 right, 3 both). Row a of DISCRETE_BUTTONS is action a's
# buttons.
DISCRETE_BUTTONS = discrete_buttons(cabinet=False)


def action_meanings(cabinet: bool, nudges: bool = True) -> list[str]:
    """The name of every discrete action, as ALE's ``get_action_meanings``: ``NOOP``, or the
    buttons it holds joined by ``_`` (``LEFT_FLIPPER``, ``BOTH_FLIPPERS_PLUNGER_NUDGE_UP``)."""
    names = []
    for action in range(len(discrete_buttons(cabinet, nudges))):
        parts = [_FLIPPER_NAMES[action & 3]]
        if cabinet:
            parts += ["PLUNGER" if action >> 2 & 1 else "", _NUDGE_NAMES[action >> 3]]
        names.append("_".join(part for part in parts if part) or "NOOP")
    return names


def discrete_action(buttons: "list[bool] | tuple[bool, ...] | np.ndarray") -> int:
    """The discrete action that holds ``buttons`` (one bool per column of :func:`button_names`;
    at most one nudge)."""
    pressed = [bool(held) for held in buttons]
    action = int(pressed[0]) | int(pressed[1]) << 1
    if len(pressed) > len(BUTTONS):
        nudges = [i for i in range(3) if pressed[3 + i]]
        if len(nudges) > 1:
            raise ValueError(f"a discrete action holds at most one nudge, got {buttons}")
        action |= int(pressed[2]) << 2 | (nudges[0] + 1 if nudges else 0) << 3
    return action


class InvalidActions(ValueError):
    """Actions that are not in the game's action space (raised before anything changes)."""


def decode_actions(
    actions: Any, action_type: str, discrete: np.ndarray, n_envs: int, n_buttons: int
) -> np.ndarray:
    """The (n_envs, buttons) bool buttons held by ``actions`` of ``action_type``: (n_envs,)
    integers for ``"discrete"`` (rows of ``discrete``, see :func:`discrete_buttons`), (n_envs,
    n_buttons) zeros and ones for ``"multibinary"``; else InvalidActions says what was
    expected."""
    actions = np.asarray(actions)
    if action_type == "discrete":
        n_actions = len(discrete)
        valid = (
            actions.shape == (n_envs,)
            and actions.dtype.kind in "biu"  # Gymnasium's Discrete takes True as 1
            and actions.min() >= 0
            and actions.max() < n_actions
        )
        if valid:  # (as integers: a bool array would index as a mask)
            return discrete[actions.astype(np.intp)]
        expected = f"({n_envs},) integers in [0, {n_actions})"
    else:
        shape = (n_envs, n_buttons)
        if actions.shape == shape and np.all((actions == 0) | (actions == 1)):
            return actions.astype(bool)
        expected = f"{shape} zeros and ones"
    raise InvalidActions(
        f"invalid actions: expected {expected} for action_type={action_type!r}, "
        f"got shape {actions.shape} dtype {actions.dtype}"
    )
