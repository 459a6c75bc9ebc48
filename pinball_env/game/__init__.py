"""The game: the rules of pinball over a batch of envs (``game.py``: :class:`Game`, actions,
launches, drains, score, reward, infos), its state (``state.py``), the buttons and actions
(``actions.py``), the infos (``infos.py``), the tables it can be played on (``playable.py``),
the compiled loop that plays a step's frames (``play.py``) by its step parameters
(``parameters.py``), a table's rules compiled (``rulebook.py``) and the several balls of a
table whose trough holds more than one (``multiball.py``: the trough, drains, locks, the
auto-plunger, the multiball's start and end)."""

from pinball_env.game.actions import (
    CABINET_BUTTONS,
    DISCRETE_BUTTONS,
    InvalidActions,
    action_meanings,
    button_names,
    discrete_action,
    discrete_buttons,
)
from pinball_env.game.game import RESET_OPTIONS, Game
from pinball_env.game.parameters import BALL_SEARCH_TIME, MAX_RUN_ON_FRAMES, StepParameters
from pinball_env.game.playable import check_playable
from pinball_env.game.state import GameState, make_game_state
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
    "StepParameters",
    "action_meanings",
    "button_names",
    "check_playable",
    "discrete_action",
    "discrete_buttons",
    "make_game_state",
]
