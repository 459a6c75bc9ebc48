"""``PinballEnv``: the Gymnasium shell around a game of one env (``PinballCore``)."""

import itertools
from collections.abc import Mapping
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium.error import ResetNeeded

from pinball_env.envs.core import CoreAttributes, PinballCore
from pinball_env.game import InvalidActions, action_meanings, discrete_action
from pinball_env.options import PinballOptions
from pinball_env.render import Window
from pinball_env.table import BUTTONS, Table


class PinballEnv(CoreAttributes, gym.Env):
    """A real flipper-and-ball pinball table; the agent works the two flipper buttons.

    ## Description

    A 27 mm steel ball on a 0.51 m x 1.07 m playfield inclined at 6.5 degrees (the default
    ``classic`` table: top arch, shooter lane and gate, three pop bumpers, two slingshots, in- and
    outlanes, two flippers, a drain). The ball moves by swept (continuous) collision in fixed
    substeps, so it never passes through a wall or a flipper; flippers swing up in 22 ms while
    their button is held and fall back in 40 ms when it is released. Balls are put into play from
    the plunger at a random speed; a game is ``balls`` balls.

    ## Action Space

    ``action_type="discrete"`` (default): ``Discrete(4)``

    | Num | Action                  |
    |-----|-------------------------|
    | 0   | no button               |
    | 1   | left flipper button     |
    | 2   | right flipper button    |
    | 3   | both buttons            |

    ``action_type="multibinary"``: ``MultiBinary(2)``, (left button, right button).
    A button acts for the whole step (one frame, 1/60 s, or ``frame_skip`` frames): held, the
    flipper swings up to its stop and stays there; released, it falls back to rest.

    **The whole cabinet** (``Pinball-v1`` and ``-v2``, a table with ``cabinet`` and ``tilt``
    sections and the player's plunger): ``Discrete(32)``, as ALE names its actions
    (:meth:`get_action_meanings`). Action ``a`` holds the flippers ``a & 3`` as above, the
    plunger if ``a & 4``, and the nudge ``a >> 3``:

    | Num   | Action                                                            |
    |-------|-------------------------------------------------------------------|
    | 0-3   | NOOP, LEFT_FLIPPER, RIGHT_FLIPPER, BOTH_FLIPPERS                  |
    | 4-7   | PLUNGER, LEFT_FLIPPER_PLUNGER, RIGHT_..., BOTH_FLIPPERS_PLUNGER    |
    | 8-15  | NUDGE_LEFT, LEFT_FLIPPER_NUDGE_LEFT, ..., BOTH_FLIPPERS_PLUNGER_NUDGE_LEFT |
    | 16-23 | NUDGE_RIGHT and the same combinations                             |
    | 24-31 | NUDGE_UP and the same combinations                                |

    ``nudge_actions=False`` leaves out the actions that nudge: ``Discrete(8)``, actions 0-7 above
    (an agent that would rather not risk the tilt; ALE's minimal action set is the like).

    ``action_type="multibinary"``: ``MultiBinary(6)``, (left, right, plunger, nudge left,
    nudge right, nudge up); nudges pressed together shove along the sum of their directions
    (left and right cancel). The plunger: while its button is held it pulls back (the
    table's ``stroke`` in ``pull_time``: 5 cm in 1 s on ``classic_v1``); let go, it fires a
    ball waiting on it at a speed linear in the pull (``pull_speed``: 0.5 m/s at the shortest
    pull to 3.6 m/s at the whole stroke, give or take the ``scatter``). A nudge shoves the
    cabinet (``nudge_impulse``, 36 N s on the 120 kg cabinet: 0.3 m/s); a nudge held or
    pressed again within ``nudge_interval``
    (0.25 s) of the last shove does nothing, the fastest the cabinet can be shoved. The cabinet
    swings back on its legs (a mass-spring-damper); the ball, simulated relative to the
    table, feels the cabinet's acceleration opposite, so a nudge moves the table under it by a
    few millimetres and back.

    On the keyboard (``get_keys_to_action``, for ``gymnasium.utils.play.play`` and
    ``python -m pinball_env.tools.play``): left flipper Left Shift, Z or the left arrow; right
    flipper Right Shift, M or the right arrow; with the cabinet, the plunger the down arrow or
    Enter, nudges X (left), N (right), the up arrow or B (up). The map holds every set of
    flipper keys and every set of at most ``MAX_CABINET_KEYS`` (4) keys with a cabinet key; in a
    discrete action the first of the nudges held (left, right, up) wins.

    ## Observation Space

    ``obs_type="state"`` (default): a ``Box`` of float32, table coordinates (x to the right,
    y up the table, origin at the bottom-left corner), for a table with two flippers:

    | Index | Observation                                   | Min   | Max   | Unit  |
    |-------|-----------------------------------------------|-------|-------|-------|
    | 0     | ball x                                        | 0     | 0.51  | m     |
    | 1     | ball y                                        | 0     | 1.07  | m     |
    | 2     | ball vx (clipped to +-20)                     | -20   | 20    | m/s   |
    | 3     | ball vy (clipped to +-20)                     | -20   | 20    | m/s   |
    | 4     | left flipper angle above rest                 | 0     | 0.873 | rad   |
    | 5     | right flipper angle above rest                | 0     | 0.873 | rad   |
    | 6     | left flipper angular velocity, + going up     | -39.7 | 39.7  | rad/s |
    | 7     | right flipper angular velocity, + going up    | -39.7 | 39.7  | rad/s |
    | 8     | ball in play (1) or game over (0)             | 0     | 1     | -     |
    | 9     | balls left, the one in play included          | 0     | balls | -     |

    The bounds come from the table (playfield size, flipper swing and speeds): for another table
    the flipper rows repeat once per flipper in the table's order. A drained ball is replaced
    at once by the next one on the plunger; after the last one the ball stays where it crossed
    the drain. A ball waiting on the player's plunger is in play (1).

    With the cabinet (``Pinball-v1``), 8 more rows (18 in all on ``classic_v1``):

    | Index | Observation                                   | Min   | Max   | Unit  |
    |-------|-----------------------------------------------|-------|-------|-------|
    | 10    | plunger pull                                  | 0     | 0.05  | m     |
    | 11    | ball waiting on the plunger (1) or not (0)    | 0     | 1     | -     |
    | 12    | cabinet offset x (clipped to +-0.02)          | -0.02 | 0.02  | m     |
    | 13    | cabinet offset y, up the table (clipped)      | -0.02 | 0.02  | m     |
    | 14    | cabinet velocity x (clipped to +-1)           | -1    | 1     | m/s   |
    | 15    | cabinet velocity y (clipped to +-1)           | -1    | 1     | m/s   |
    | 16    | tilt warnings standing                        | 0     | 3     | -     |
    | 17    | tilted (1) or not (0)                         | 0     | 1     | -     |

    (the pull's maximum is the table's stroke, in strokes (0-1) for generated tables; the
    warnings' is the table's allowed warnings + 1).

    With rules (a table with a ``rules`` section: ``Pinball-v1``), more rows (29 in all on
    ``classic_v1``): each of the rules' lights, drop targets and kickbacks, each timer's share
    of its time left, each counter, the bonus multiplier and the bonus:

    | Index | Observation (``classic_v1``)                  | Min   | Max   | Unit   |
    |-------|-----------------------------------------------|-------|-------|--------|
    | 18-20 | lights ``lane_1_lit`` to ``lane_3_lit`` (1 lit)| 0     | 1     | -      |
    | 21-23 | drop targets ``drop_1`` to ``drop_3`` (1 up)   | 0     | 1     | -      |
    | 24    | kickback ``left_kickback`` lit (1)            | 0     | 1     | -      |
    | 25    | ``bumper_frenzy``'s time left, of its 20 s    | 0     | 1     | -      |
    | 26    | counter ``banks_down`` (clipped to 100)       | 0     | 100   | -      |
    | 27    | bonus multiplier                              | 1     | 5     | x      |
    | 28    | end-of-ball bonus (clipped to 100)            | 0     | 100   | 1000 points |

    ``rays`` come after these rows. ``observation_rows`` gives every row of the env as made
    (meaning, min, max, unit), from the declaration its space is built from.

    ``obs_type="rgb"``: a ``Box(0, 255, (84, 84, 3), uint8)`` picture of the whole table (stretched
    to the image), drawn without a display; ``obs_type="grayscale"``: the same as
    ``(84, 84, 1)`` luminance. ``image_size`` changes the size.

    ## Rewards

    The points of the step's scoring events times ``reward_scale`` (default 0.01): a pop bumper
    is 100 points (reward 1), a slingshot or a rollover 10 (0.1); on ``classic_v1`` the skill
    shot 1000 (10); with rules, the points the rules award, and the end-of-ball bonus times
    its multiplier where a ball is lost. A tilted machine scores nothing. Optional shaping, off
    by default: ``height_shaping`` times the rise of the ball during the step in table heights
    (a potential, so it sums to ``height_shaping`` times the net rise of each ball, from its
    launch to where it drains); ``drain_penalty`` taken off for each ball that drains;
    ``bonus_shaping`` pays the end-of-ball bonus's reward as it is earned.

    ## Starting State

    Flippers at rest, score 0, ``balls`` balls to play; the first ball is fired up the shooter
    lane at a speed drawn uniformly from the table's plunger range (2.2-3.2 m/s on ``classic``).
    With the cabinet, the cabinet and its plumb bob at rest, no warnings, and each ball waits
    at rest on the plunger for the player (``info["ball_on_plunger"]``).
    ``reset(options={"ball_position": [x, y], "ball_velocity": [vx, vy]})`` (metres, metres per
    second; either key alone is allowed) puts the ball in play at that state instead, for tests
    and curricula. The state is checked as a table file is: inside the outline, clear of every
    element, somewhere a ball in play can get to from the plunger (not inside a slingshot, not
    below the drain), at most 100 m/s.

    ## Episode End

    Termination: the last ball drains (the game is over). Truncation: only by the ``TimeLimit``
    wrapper, ``max_episode_steps=7200`` (two minutes of play) for ``Pinball-v0``; it counts
    steps, so with ``frame_skip=k`` pass ``max_episode_steps=7200 // k`` for the same two
    minutes. Every game can
    end: a ball in play that has not moved a ball radius in 10 s (resting in the shooter lane,
    or held in a flipper's cradle) is served again from the plunger, as a real machine's ball
    search would, without losing a ball. Stepping before the first ``reset`` raises Gymnasium's
    ``ResetNeeded``.

    ``info`` (reset and step): ``ball_position``, ``ball_velocity`` (float64 arrays, m and m/s),
    ``score`` (points this game), ``balls_left``, ``events`` (scoring element name -> hits this
    step), ``points`` (this step), ``drained`` (a ball drained this step) and ``frames``
    (frames played in this game).

    **The cabinet's rules** (``Pinball-v1``). A ball that falls back down the shooter lane
    waits on the plunger again; a ball that has stayed in the shooter lane for 10 s
    (BALL_SEARCH_TIME: waiting, or plunged too softly and fallen back) is fired by the machine
    at a speed drawn from the plunger's range, so every game still ends. The skill shot: the
    rollover ``skill_lane`` (under the top arch, on the right) is lit for 1.25 s after the
    player's plunge and scores 1000 points if crossed while lit: a pull of 56 frames (of the 60
    of the whole stroke) makes it nearly always. The plunge's speed varies by up to the table's
    ``scatter`` (0.05 m/s), drawn from the env's random stream. The tilt: a plumb bob (a
    0.1 m pendulum) swings with the cabinet; each time it touches its ring (5 degrees from
    vertical) is a warning, forgotten after 10 s without another; the touch after 2 warnings
    tilts the machine: the flippers and kickers go dead, nothing scores, the ball is lost
    (at once if it waits on the plunger; else where it drains, or where it lies still for 10
    s) and play goes on with the next ball, the tilt and the warnings cleared. One nudge swings
    the bob about 2.5 degrees; nudges left and right in a rhythm build its swing up. **v1's
    tilt ignores one-way nudging**: shoves in one direction, even four a second, never reach
    its ring. ``Pinball-v2`` (``classic_v2``: v1's table with the ring at 1 degree, Visual
    Pinball X's default, and ``settle_time`` 1 s) is the one to use: there a firm shove swings
    the bob onto its ring whatever it was doing, so every nudge is a warning (touches within
    1 s of one are that one), and any sustained nudging, one way or alternating, tilts the
    machine within about two seconds; a single nudge, or one every 10 s, never does.
    ``info`` adds ``tilt_warnings``, ``tilted`` (the machine is tilted, or tilted in this
    step), ``ball_on_plunger``, ``plunger_pull`` [m], ``cabinet_offset`` [m] and ``skill_shot``
    (made in this step).

    **Rules and targets** (``Pinball-v1``; any table with ``drop_targets``, ``standup_targets``,
    ``spinners``, ``kickbacks``, ``ball_save`` or ``rules``, see ``pinball_env.table.rules``).
    On ``classic_v1``: the top lanes ``lane_1`` to ``lane_3`` light when rolled over (100 to the
    bonus); each flipper press passes the lit lanes one place to the right (lane change); all
    three lit raise the bonus multiplier (x2 to x5) and score 500. The drop bank (three targets
    on the right, 100 each and 200 to the bonus) rises 1 s after its last target falls; the
    whole bank scores 1000, doubles the pop bumpers for 20 s (``bumper_frenzy``) and lights the
    kickback in the left outlane, which fires the next ball that reaches it back into play and
    goes dark; every third bank is an extra ball. The spinner on the left orbit scores 10 a
    revolution (and 20 to the bonus), the stand-up target 200 (and 500 to the bonus). A ball
    lost scores the bonus times the multiplier (nothing on a tilt); both then start again. A
    ball that drains within 6 s of its launch is served again, once per ball (ball save).
    ``info`` adds ``rule_events`` (rule name -> times it fired this step; ``"ball saved"`` and
    ``"end-of-ball bonus"`` too), ``bonus`` [points], ``bonus_multiplier`` and ``rule_score``
    (points the rules scored this game; the rest came from hits).

    ## Generated tables (``PinballProcgen-v0``)

    ``table="generated"`` (what ``PinballProcgen-v0`` registers) plays every game on a layout,
    a table generated from a seed (``pinball_env.procgen.generate_table``), so that an agent
    can be trained on some layouts and tested on others, as in Procgen. Layouts are the seeds
    ``[start_layout, start_layout + num_layouts)`` (``num_layouts=0``: unlimited,
    ``[start_layout, start_layout + 2**31)``); each reset draws one uniformly with the env's
    random generator (``reset(seed=...)`` fixes the sequence), or plays the one given as
    ``reset(options={"layout": seed})``. ``difficulty``: ``"easy"`` or ``"hard"`` tables.
    ``info["layout"]`` (and the attribute ``layout``) is the layout of the game. The state
    observation is then normalised to the table, so that it means the same on every layout:
    ball x and y in table widths and heights (0-1), vx and vy [m/s] (clipped to +-20), each
    flipper's angle above rest in swings (0-1) and angular velocity in top speeds (-1..1),
    ball in play, balls left. Images are each game's own table. ``render_mode`` frames have one
    size for every layout of a difficulty, so that video recorders and windows take them: the
    playfield part is ``envs.frame_size`` (360 x 792 pixels), each table fitted into it with
    its aspect kept and centred, the scoreboard beside it: (792, 470, 3) uint8. The table of
    each env's next game is generated in the background while this one is played.

    ``rays=K`` (any table): K more entries after the state observation, the distances from the
    ball's centre to the first wall, post or flipper along K directions evenly round the
    circle (the first along +x, counter-clockwise), in 0.5 m (1: nothing that near), so that a
    state policy can see the layout.

    ## Arguments

    ```python
    gym.make("Pinball-v0", table="classic", obs_type="state", action_type="discrete", balls=3,
             reward_scale=0.01, height_shaping=0.0, drain_penalty=0.0, bonus_shaping=0.0,
             frame_skip=1, skip_above=0.0, repeat_action_probability=0.0, max_frames=None,
             image_size=(84, 84), physics="swept",
             render_mode=None, num_layouts=0, start_layout=0, difficulty="easy", targets=False,
             rays=0)
    gym.make("PinballProcgen-v0", num_layouts=16, ...)  # table="generated", the rest the same
    ```

    The options are ``pinball_env.options.PinballOptions`` (each checked when the env is
    made); ``PinballEnv(options)`` takes them as one record, keywords replacing any of them.

    ```python
    PinballEnv(PinballOptions(frame_skip=4), balls=1)
    ```

    - ``table``: a built-in table name (``"classic"``; the built-in tables are package data in
      ``pinball_env/table/tables``), a generated one (``"procgen:SEED"``,
      ``"procgen-hard:SEED"``), a path to a table YAML file, a ``Table``, or ``"generated"`` (a
      generated table every game, above). A game needs a plunger, flippers, a closed outline
      and a drain (``"box"`` is a physics test box without them).
    - ``obs_type``: ``"state"``, ``"rgb"`` or ``"grayscale"``.
    - ``action_type``: ``"discrete"`` or ``"multibinary"``.
    - ``nudge_actions``: with the cabinet and discrete actions, False leaves out the actions
      that nudge (``Discrete(8)``; the game is the same).
    - ``balls``: balls per game (>= 1).
    - ``reward_scale``: reward per point.
    - ``height_shaping``: weight of the optional height shaping term (0 = off).
    - ``drain_penalty``: reward taken off for each ball that drains (0 = off).
    - ``bonus_shaping``: a training aid on a table with rules, 0 (off) to 1: that share of the
      end-of-ball bonus's reward is paid as the bonus is earned (each frame, the change of the
      bonus times the multiplier, times ``reward_scale``) and taken off where it is scored, so
      that losing a ball never looks like a way to collect it. The score is unchanged.
    - ``frame_skip``: frames per step (1-60), the action held on each; rewards, ``points`` and
      ``drained`` are summed over them, and a game that ends stops there.
    - ``skip_above``: a training aid, 0 (off) or a height in table heights (0-1): after the
      step's frames, while the ball is in play above that height, the buttons are released and
      the step runs on (up to 60 more frames), so that the agent is asked only while the ball
      is low, near the flippers.
    - ``repeat_action_probability``: sticky actions, as ALE v5's (Machado et al. 2018), in
      [0, 1): each frame, with this probability, the buttons the frame before pressed are
      pressed again instead of the action's (the frames of ``frame_skip`` and ``skip_above``
      each draw). The draws come from the env's own random stream (``np_random``), one per
      frame the step may play, drawn when the step starts; 0 (the default) draws nothing, so
      games are as they were. The benchmark protocol evaluates with 0.25
      (``pinball_env.protocol``).
    - ``max_frames``: None, or the frames a game lasts: the step that reaches it stops there
      and returns ``truncated`` (a time limit in frames, whatever the frame skip; the
      ``TimeLimit`` wrapper's ``max_episode_steps`` counts steps).
    - ``image_size``: (height, width) of image observations, in pixels, or one int for a square.
    - ``physics``: ``"swept"`` (ours, continuous collision) or ``"pymunk"`` (the same table in
      pymunk, for cross-checks, on a fixed table; needs the ``crosscheck`` extra).
    - ``num_layouts``, ``start_layout``, ``difficulty``, ``targets``: the layouts of
      ``table="generated"`` (an error with any other table); ``targets=True``: generated tables
      get a drop bank and a spinner (``"procgen+targets:SEED"``; the observation keeps its
      shape; False keeps the tables as they were).
    - ``rays``: ray distances after the state observation (0-64).
    - ``render_mode``: ``"human"`` (a pygame window at real speed, frame rate over
      ``frame_skip`` steps per second, needs the ``render`` extra; ``metadata["render_fps"]`` is
      that rate rounded to an int, at least 1) or ``"rgb_array"`` (an aspect-correct uint8
      HxWx3 frame, no display needed). A frame shows the playfield (the ball where it drained
      once the game is over) and beside it a scoreboard with the score and the balls left;
      with the cabinet also the plunger pulled back (drawn at a smaller scale where the table
      has no room below it), the cabinet's shake (twice its offset) and, on the scoreboard,
      the tilt warnings and TILT.

    ## Version History

    - v2: v1's game with a tilt that any sustained nudging trips (``classic_v2``: the ring at
      1 degree, ``settle_time`` 1 s): every nudge is a warning. The benchmark protocol's env.
    - v1: the whole cabinet on ``classic_v1`` (the classic layout): the player's plunger and a
      skill shot, the nudge, the plumb-bob tilt; 32 actions. Then rules and targets on
      ``classic_v1`` (top lanes with lane change and the bonus multiplier, a drop bank, a
      spinner, a stand-up, a kickback, ball save; the observation's rule rows, 29 in all),
      which changed v1's games and scores. (``gym.make("Pinball-v0")`` now
      says that v1 exists, as Gymnasium does for every older version; v0's games are bitwise
      unchanged.)
    - v0: first release: swept collision against walls, posts and rotating flippers.
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["human", "rgb_array"], "render_fps": 60}
    # The keyboard's flipper buttons (pygame key names), by button: get_keys_to_action's map,
    # which gymnasium.utils.play and python -m pinball_env.tools.play both use.
    FLIPPER_KEYS: ClassVar[dict[str, tuple[str, ...]]] = {
        "left": ("K_LSHIFT", "K_z", "K_LEFT"),
        "right": ("K_RSHIFT", "K_m", "K_RIGHT"),
    }
    # The cabinet's buttons (a table with one, Pinball-v1), the same way.
    CABINET_KEYS: ClassVar[dict[str, tuple[str, ...]]] = {
        "plunger": ("K_DOWN", "K_RETURN"),
        "nudge_left": ("K_x",),
        "nudge_right": ("K_n",),
        "nudge_up": ("K_UP", "K_b"),
    }
    # A cabinet table's 12 keys have 4095 sets: its map holds every set of flipper keys (as a
    # table without a cabinet) and every set of at most this many keys with a cabinet key
    # (both flippers, the plunger and a nudge at once), 800 in all.
    MAX_CABINET_KEYS: ClassVar[int] = 4

    def __init__(self, options: PinballOptions | None = None, **kwargs: Any) -> None:
        if options is None or kwargs:
            base = {} if options is None else options.to_kwargs()
            options = PinballOptions.from_kwargs(type(self).__name__, {**base, **kwargs})
        self.options = options
        self.core = PinballCore(options)
        self.render_mode = options.render_mode
        self.steps_per_second = self.core.steps_per_second
        self.metadata = {**self.metadata, "render_fps": self.core.render_fps}
        self.action_space = self.core.action_space
        self.observation_space = self.core.observer.space
        self._reset_done = False
        self._window: Window | None = None

    # --- Gymnasium API ----------------------------------------------------------------------

    def reset(
        self, *, seed: int | None = None, options: Mapping[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        if seed is not None:
            self.core.seeded([0])
        self.core.new_games([0], [self.np_random], options)
        self._reset_done = True
        if self.render_mode == "human":
            self.render()
        return self.core.observe()[0], self.core.info(0)

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        if not self._reset_done:
            raise ResetNeeded("call reset() before step(): no game has started")
        try:  # the game checks the action, before anything changes
            reward, game_over = self.game.step(np.asarray(action)[None], [self.np_random])
        except InvalidActions:
            raise ValueError(
                f"invalid action {action!r}: expected an element of {self.action_space}"
            ) from None
        if self.render_mode == "human":
            self.render()
        out_of_time = bool(self.game.out_of_time()[0])
        obs, info = self.core.observe()[0], self.core.info(0)
        return obs, float(reward[0]), bool(game_over[0]), out_of_time, info

    def render(self) -> np.ndarray | None:
        if self.render_mode is None:
            gym.logger.warn(
                "render() called without a render_mode; pass render_mode='rgb_array' or "
                "'human' to gym.make"
            )
            return None
        frame = self.core.frame(0)
        if self.render_mode == "rgb_array":
            return frame
        if self._window is None:
            self._window = Window((frame.shape[1], frame.shape[0]), self.steps_per_second)
        self._window.show(frame)
        return None

    def close(self) -> None:
        self.core.close()
        if self._window is not None:
            self._window.close()
            self._window = None

    def __getstate__(self) -> dict[str, Any]:
        # A pygame window cannot be pickled; a copy opens its own when it first renders.
        state = self.__dict__.copy()
        state["_window"] = None
        return state

    def get_keys_to_action(self) -> dict[tuple[int, ...], int | np.ndarray]:
        """The keyboard map of ``gymnasium.utils.play.play``: a set of keys (a sorted tuple of
        pygame key codes) -> the action pressing the buttons of its keys. Keys are the
        :attr:`FLIPPER_KEYS` and, on a table with the cabinet, the :attr:`CABINET_KEYS`; the map
        has every non-empty set of flipper keys and, with the cabinet, every set of at most
        :attr:`MAX_CABINET_KEYS` keys that holds a cabinet key (``play`` looks up the exact set
        held: a larger one is no action). Actions are ints for ``action_type="discrete"`` and
        int8 arrays of the buttons (``game.button_names``) for ``"multibinary"`` (then pass
        ``noop=np.zeros(env.action_space.n, np.int8)`` to ``play``, whose default noop, 0, is
        not a MultiBinary action). A discrete action holds one nudge: with
        several nudge keys held, the first of nudge left, right, up wins (a button array presses
        them all; left and right cancel). Needs pygame for the key codes."""
        pygame = Window.import_pygame()
        names = self.game.button_names
        declared = {**self.FLIPPER_KEYS, **self.CABINET_KEYS}
        keys = [
            (getattr(pygame, name), button)
            for button, names_of_button in enumerate(declared[b] for b in names)
            for name in names_of_button
        ]
        flippers = len(BUTTONS)  # buttons before these are the flippers'
        nudges = [i for i, name in enumerate(names) if name.startswith("nudge")]
        # play looks up exactly the set of keys held, so every combination needs an entry.
        mapping: dict[tuple[int, ...], int | np.ndarray] = {}
        for count in range(1, len(keys) + 1):
            for combination in itertools.combinations(keys, count):
                buttons = [button for _, button in combination]
                if count > self.MAX_CABINET_KEYS and max(buttons) >= flippers:
                    continue
                pressed = np.zeros(len(names), dtype=bool)
                pressed[buttons] = True
                codes = tuple(sorted(code for code, _ in combination))
                if self.action_type == "discrete":
                    held = [i for i in nudges if pressed[i]]
                    # The first nudge wins; without nudge actions, nudge keys do nothing.
                    pressed[held[1:] if self.options.nudge_actions else held] = False
                    mapping[codes] = discrete_action(pressed)
                else:
                    mapping[codes] = pressed.astype(np.int8)
        return mapping

    def get_action_meanings(self) -> list[str]:
        """The name of every discrete action, as ALE's envs have it: ``NOOP``, ``LEFT_FLIPPER``,
        ``RIGHT_FLIPPER``, ``BOTH_FLIPPERS`` and, on a table with the cabinet (``Pinball-v1``),
        their combinations with ``PLUNGER`` and one of ``NUDGE_LEFT``, ``NUDGE_RIGHT``,
        ``NUDGE_UP``, joined by ``_`` (action ``a``: flippers ``a & 3``, plunger bit 2, nudge
        ``a >> 3``). With ``action_type="multibinary"`` these are the discrete actions'
        names all the same; the buttons are ``game.button_names``."""
        return action_meanings(self.game.cabinet, self.options.nudge_actions)

    # --- what the env is playing -------------------------------------------------------------

    @property
    def table(self) -> Table:
        """The table of the game (of the game being played, with generated tables)."""
        return self.game.world.table_of(0)

    @property
    def layout(self) -> int | None:
        """The layout of the game (generated tables), else None."""
        return None if self.core.layout is None else int(self.core.layout[0])
