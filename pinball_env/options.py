"""Every option of the pinball envs, declared once: its type, default, range and meaning.

:class:`PinballOptions` holds the options of a game (``gym.make("Pinball-v0", **options)``), and
:class:`VectorOptions` those a vector env adds (``gym.make_vec``). Both check every value when
made, so a config's env options can be checked without building an env; ``Game``, the envs and
``agents.config`` all take them.
"""

import dataclasses
import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from gymnasium.vector import AutoresetMode

from pinball_env import checks
from pinball_env.sim.backends import PHYSICS
from pinball_env.sim.parallel import check_threads
from pinball_env.table import Table

# A game's time: two minutes of play at 60 frames per second [frames].
GAME_FRAMES = 7200
# The registered time limit [steps]: the game's time at frame_skip 1 (TimeLimit counts steps; the
# max_frames option counts frames whatever the frame skip).
MAX_EPISODE_STEPS = GAME_FRAMES
# Most frames one step may hold an action for (a second at 60 Hz).
MAX_FRAME_SKIP = 60
# Rays a state observation may carry (see ``rays``).
MAX_RAYS = 64
# The table source that draws a generated table at every game (num_layouts, start_layout,
# difficulty and targets say which).
GENERATED = "generated"
OBS_TYPES = ("state", "rgb", "grayscale")
ACTION_TYPES = ("discrete", "multibinary")
# Which balls skip_above watches: the game's ball (the first in play), or every ball in play.
SKIP_ABOVE_BALLS = ("first", "all")
# The order of the state observation's ball blocks (tables of several balls): by slot, or the
# lowest ball in play first (the one nearest the flippers: see ``observation.balls_observation``).
BALL_ORDERS = ("slot", "lowest")
RENDER_MODES = ("human", "rgb_array")
from pinball_env.procgen import DIFFICULTIES, check_difficulty, layout_seeds  # noqa: E402

# The options that only the generated-table source takes.
LAYOUT_OPTIONS = ("num_layouts", "start_layout", "difficulty", "targets")


def _option(default: Any, check: Callable[[str, Any], Any] | None = None) -> Any:
    """A dataclass field with its default and the check that validates (and normalises) it."""
    return field(default=default, metadata={"check": check})


def _table(name: str, value: object) -> object:
    if not isinstance(value, (str, os.PathLike, Table)):
        raise ValueError(
            f"{name} must be a table name, a path to a table YAML file, a Table or "
            f"{GENERATED!r}, got {value!r}"
        )
    return value


def _image_size(name: str, size: object) -> tuple[int, int]:
    pair = (size, size) if checks.is_int(size) else size
    if not (
        isinstance(pair, (tuple, list))
        and len(pair) == 2
        and all(checks.is_int(n) for n in pair)
        and min(pair) >= 16
    ):
        raise ValueError(f"{name} must be an int or (height, width) ints, each >= 16, got {size!r}")
    return int(pair[0]), int(pair[1])


def _choice(*choices: object) -> Callable[[str, Any], Any]:
    def check(name: str, value: object) -> object:
        checks.choice(name, value, choices)
        return value

    return check


def _at_least(low: int, high: int | None = None) -> Callable[[str, Any], int]:
    return lambda name, value: checks.integer(name, value, low, high)


def _rays(name: str, value: object) -> int:
    if not checks.is_int(value):
        raise ValueError(f"{name} must be an integer, got {value!r}")
    if not 0 <= value <= MAX_RAYS:
        raise ValueError(f"{name} must be in [0, {MAX_RAYS}], got {value}")
    return int(value)


def _autoreset_mode(name: str, mode: object) -> AutoresetMode:
    try:
        return AutoresetMode(mode)
    except ValueError:
        allowed = ", ".join(repr(m.value) for m in AutoresetMode)
        raise ValueError(f"{name} must be one of {allowed}, got {mode!r}") from None


class _Checked:
    """Checks every field with its ``check`` when made; :meth:`from_kwargs` names unknown keys."""

    def __post_init__(self) -> None:
        for spec in dataclasses.fields(self):  # type: ignore[arg-type]
            check = spec.metadata.get("check")
            if check is not None:
                object.__setattr__(self, spec.name, check(spec.name, getattr(self, spec.name)))

    @classmethod
    def names(cls) -> tuple[str, ...]:
        return tuple(spec.name for spec in dataclasses.fields(cls))  # type: ignore[arg-type]

    @classmethod
    def from_kwargs(cls, owner: str, kwargs: Mapping[str, Any]) -> Any:
        """The options of ``kwargs``; a TypeError names any key that is not one of them."""
        unknown = sorted(map(repr, set(kwargs) - set(cls.names())))
        if unknown:
            raise TypeError(
                f"{owner} got unexpected keyword argument(s) {', '.join(unknown)}, not its "
                f"options ({', '.join(cls.names())})"
            )
        return cls(**kwargs)

    def to_kwargs(self) -> dict[str, Any]:
        """The options as keyword arguments (for ``gym.make``)."""
        return {name: getattr(self, name) for name in self.names()}


@dataclass(frozen=True)
class PinballOptions(_Checked):
    """The options of a pinball game (see ``PinballEnv`` for what each does)."""

    table: str | os.PathLike[str] | Table = _option("classic", _table)
    """A built-in table name, ``"procgen:SEED"``, a path to a table YAML file, a ``Table``, or
    ``"generated"``: a generated table every game (``PinballProcgen-v0``)."""
    obs_type: str = _option("state", _choice(*OBS_TYPES))
    """``"state"``, ``"rgb"`` or ``"grayscale"``."""
    action_type: str = _option("discrete", _choice(*ACTION_TYPES))
    """``"discrete"`` (``Discrete(4)``) or ``"multibinary"`` (``MultiBinary(2)``)."""
    nudge_actions: bool = _option(True, checks.flag)
    """Tables with the cabinet, discrete actions: False leaves out the 24 actions that nudge
    (``Discrete(8)``: the flippers with or without the plunger, numbered as in the full set), as
    ALE's minimal action set leaves out what a player need not press. The game is the same."""
    balls: int = _option(3, _at_least(1))
    """Balls per game (>= 1)."""
    reward_scale: float = _option(0.01, checks.finite)
    """Reward per point."""
    height_shaping: float = _option(0.0, checks.finite)
    """Weight of the height shaping term, the ball's rise in table heights (0: off)."""
    drain_penalty: float = _option(0.0, checks.finite)
    """Reward taken off for each ball that drains (0: off)."""
    bonus_shaping: float = _option(0.0, checks.finite)
    """Share of the end-of-ball bonus's reward paid as it is earned (tables with rules; 0: off)."""
    frame_skip: int = _option(1, _at_least(1, MAX_FRAME_SKIP))
    """Frames per step (1-60), the action held on each."""
    skip_above: float = _option(0.0, checks.fraction)
    """0 (off), or a height in table heights (0-1) above which a step runs on, buttons released."""
    skip_above_balls: str = _option("first", _choice(*SKIP_ABOVE_BALLS))
    """Which balls ``skip_above`` watches: ``"first"`` (the game's ball, the first in play) or
    ``"all"`` (the step runs on only while every free ball in play is above the height)."""
    repeat_action_probability: float = _option(0.0, checks.fraction)
    """Sticky actions (ALE v5's, Machado et al. 2018): each frame, with this probability (drawn
    from the env's own random stream), the buttons of the frame before are pressed instead of
    the action's (0: off; 0.25 in the benchmark protocol, for evaluation)."""
    max_frames: int | None = _option(None, lambda name, v: checks.optional_integer(name, v, 1))
    """None, or the frames a game lasts before it is truncated (a time limit in frames)."""
    image_size: int | tuple[int, int] = _option((84, 84), _image_size)
    """(height, width) of image observations in pixels (each >= 16), or one int for a square."""
    physics: str = _option("swept", _choice(*PHYSICS))
    """``"swept"`` (ours) or ``"pymunk"`` (the same table in pymunk, for cross-checks)."""
    render_mode: str | None = _option(None, _choice(None, *RENDER_MODES))
    """None, ``"human"`` (a window at real speed) or ``"rgb_array"`` (frames)."""
    num_layouts: int = _option(0, _at_least(0))
    """Generated tables: the layouts played, seeds [start_layout, start_layout + num_layouts)
    (0: unlimited)."""
    start_layout: int = _option(0, _at_least(0))
    """Generated tables: the first layout's seed."""
    difficulty: str = _option("easy", lambda _, value: check_difficulty(value))
    """Generated tables: ``"easy"`` or ``"hard"`` layouts."""
    targets: bool = _option(False, checks.flag)
    """Generated tables get a drop bank and a spinner (PinballProcgen-v0's tables; False keeps
    them as they were)."""
    rays: int = _option(0, _rays)
    """Ray distances from the ball appended to the state observation (0-64, 0: none)."""
    ball_order: str = _option("slot", _choice(*BALL_ORDERS))
    """The state observation's ball blocks (tables of several balls): ``"slot"`` (slot order)
    or ``"lowest"`` (the balls in play lowest first, then the held ones, then the trough's)."""

    def __post_init__(self) -> None:
        super().__post_init__()
        if not self.nudge_actions and self.action_type != "discrete":
            raise ValueError(
                f"nudge_actions=False leaves out discrete actions, not buttons of "
                f"action_type={self.action_type!r}"
            )
        if self.rays and self.obs_type != "state":
            raise ValueError(
                f"rays are part of the state observation, not of obs_type={self.obs_type!r}"
            )
        if self.ball_order != _default("ball_order") and self.obs_type != "state":
            raise ValueError(
                f"ball_order={self.ball_order!r} orders the state observation's ball blocks, "
                f"not obs_type={self.obs_type!r}"
            )
        if self.skip_above_balls != _default("skip_above_balls") and not self.skip_above:
            raise ValueError(
                f"skip_above_balls={self.skip_above_balls!r} says which balls skip_above "
                "watches: set skip_above too"
            )
        if not self.generated:
            given = [name for name in LAYOUT_OPTIONS if getattr(self, name) != _default(name)]
            if given:
                raise ValueError(
                    f"{', '.join(given)}: options of generated tables (table={GENERATED!r}), "
                    f"not of table {self.table!r}"
                )
        elif self.physics != "swept":
            raise ValueError(f"physics={self.physics!r} plays one fixed table, not generated ones")
        else:
            layout_seeds(self.num_layouts, self.start_layout)

    @property
    def generated(self) -> bool:
        """A generated table every game (``table="generated"``)."""
        return isinstance(self.table, str) and self.table == GENERATED


@dataclass(frozen=True)
class VectorOptions(_Checked):
    """The options a vector env adds to :class:`PinballOptions` (see ``PinballVectorEnv``)."""

    num_envs: int = _option(1, _at_least(1))
    """Games stepped together."""
    max_episode_steps: int | None = _option(
        MAX_EPISODE_STEPS, lambda name, v: checks.optional_integer(name, v, 1)
    )
    """Truncation after this many steps of an episode (None: never)."""
    num_threads: int | None = _option(None, lambda _, v: None if v is None else check_threads(v))
    """Threads that share the envs (None: one per core while each has 32 envs or more)."""
    autoreset_mode: AutoresetMode | str = _option(AutoresetMode.NEXT_STEP, _autoreset_mode)
    """Gymnasium's ``AutoresetMode`` (or its value): ``NextStep``, ``SameStep`` or ``Disabled``."""


def _default(name: str) -> Any:
    return PinballOptions.__dataclass_fields__[name].default


def split_options(owner: str, kwargs: Mapping[str, Any]) -> tuple[PinballOptions, VectorOptions]:
    """A vector env's keyword arguments as its game options and its vector options."""
    vector = {key: value for key, value in kwargs.items() if key in VectorOptions.names()}
    game = {key: value for key, value in kwargs.items() if key not in vector}
    return PinballOptions.from_kwargs(owner, game), VectorOptions.from_kwargs(owner, vector)


__all__ = [
    "ACTION_TYPES",
    "BALL_ORDERS",
    "DIFFICULTIES",
    "GAME_FRAMES",
    "GENERATED",
    "MAX_EPISODE_STEPS",
    "MAX_FRAME_SKIP",
    "MAX_RAYS",
    "OBS_TYPES",
    "SKIP_ABOVE_BALLS",
    "PinballOptions",
    "VectorOptions",
    "split_options",
]
