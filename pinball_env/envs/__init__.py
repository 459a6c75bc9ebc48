"""The Gymnasium shells: ``PinballEnv`` (one game) and ``PinballVectorEnv`` (N games in one
batch), both thin shells over ``PinballCore`` (the game, its table source, its observer);
``table="generated"`` draws a generated table every game (``Layouts``); a game saved and
restored is a ``PinballState`` (``states``)."""

from pinball_env.envs.core import PinballCore
from pinball_env.envs.layouts import Layouts, frame_size, layout_table
from pinball_env.envs.single import PinballEnv, unwrapped_pinball
from pinball_env.envs.states import PinballState
from pinball_env.envs.vector import EnvAttribute, PinballVectorEnv, default_threads

__all__ = [
    "EnvAttribute",
    "Layouts",
    "PinballCore",
    "PinballEnv",
    "PinballState",
    "PinballVectorEnv",
    "default_threads",
    "frame_size",
    "layout_table",
    "unwrapped_pinball",
]
