"""The game: the rules of pinball over a batch of envs (``rules.py``: actions, launches, drains,
score, reward, infos) and the compiled loop that plays a step's frames (``play.py``)."""

from pinball_env.game.actions import (
    CABINET_BUTTONS,
    action_meanings,
    button_names,
    discrete_action,
    discrete_buttons,
)
from pinball_env.game.rules import (
    BALL_SEARCH_TIME,
    DISCRETE_BUTTONS,
    MAX_RUN_ON_FRAMES,
    RESET_OPTIONS,
    Game,
    GameState,
    InvalidActions,
    check_playable,
)
from pinball_env.options import ACTION_TYPES, MAX_FRAME_SKIP

__all__ = [
    "ACTION_TYPES",
    "BALL_SEARCH_TIME",
    "CABINET_BUTTONS",
    "DISCRETE_BUTTONS",
    "MAX_FRAME_SKIP",
    "MAX_RUN_ON_FRAMES",
    "RESET_OPTIONS",
    "Game",
    "GameState",
    "InvalidActions",
    "action_meanings",
    "button_names",
    "check_playable",
    "discrete_action",
    "discrete_buttons",
]
