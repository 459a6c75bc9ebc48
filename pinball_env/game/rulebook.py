"""A table's rules (``table.rules``) compiled for the step loop: :class:`RuleBook` holds them as
arrays, :func:`run_rules` plays them for one env after a frame's physics, and
:func:`end_of_ball` scores the bonus when a ball is lost.

The rules' per-env state (lights, counters, timers, bonus, multiplier, the ball save) is in the
game's ``GameState``; the multiball's effects (``release_lock``, ``add_balls``, ``ball_save``)
are requests there that ``game.multiball`` carries out, and its triggers (``multiball_starts``,
``multiball_ends``) are ``GameState.multiball_events``, set by it after each frame's physics;
the targets' (up or down, lit or dark) is the kernel's ``State``.
"""

from typing import NamedTuple

import numpy as np
from numba import njit

from pinball_env.table import Table
from pinball_env.table.rules import EFFECTS, TRIGGERS, Effect, Trigger

# Trigger and effect kinds as the compiled code numbers them (indices of the tuples).
(HIT, BANK, FLIPPER, TIMER_ENDS, LIGHTS_ON, COUNTER, LOCKED, MULTIBALL_STARTS,
 MULTIBALL_ENDS) = (TRIGGERS.index(k) for k in (
    "hit", "bank", "flipper", "timer_ends", "lights_on", "counter", "locked", "multiball_starts",
    "multiball_ends"))  # fmt: skip
(LIGHT, UNLIGHT, ROTATE, COUNT, START_TIMER, SCORE, BONUS, MULTIPLIER, LIGHT_KICKBACK,
 EXTRA_BALL, RELEASE_LOCK, ADD_BALLS, BALL_SAVE) = range(len(EFFECTS))  # fmt: skip
# At most this many timers (the compiled code keeps those that end in a frame as bits).
MAX_TIMERS = 63


class RuleBook(NamedTuple):
    """A table's rules as arrays (every env of a game plays the same rules). Lists of ids are
    padded with -1."""

    active: bool  # the table has rules or a ball save
    order: np.ndarray  # (R,) int64: the rules in the order they run (RuleSet.order)
    trigger_kind: np.ndarray  # (R,) int64
    trigger_arg: np.ndarray  # (R,) int64: the bank, counter or timer
    trigger_at: np.ndarray  # (R,) int64: a counter trigger's count
    trigger_ids: np.ndarray  # (R, n) int64: element ids (hit, locked), lights (lights_on),
    # flippers
    guard: np.ndarray  # (R,) int64: the light that must be lit for the rule to fire (-1: none)
    effect_start: np.ndarray  # (R + 1,) int64: rule r's effects are rows start[r]:start[r + 1]
    effect_kind: np.ndarray  # (X,) int64
    effect_arg: np.ndarray  # (X,) int64: the counter, timer, kickback or lock
    effect_value: np.ndarray  # (X,) int64: points, steps, balls, frames (ball_save)
    effect_lights: np.ndarray  # (X, L) int64: the lights acted on, in order
    timer_frames: np.ndarray  # (Tm,) int64: how long each timer runs [frames]
    timer_factor: np.ndarray  # (Tm,) int64
    timer_ids: np.ndarray  # (Tm, n) int64: the element ids whose points it multiplies
    target_bank: np.ndarray  # (T,) int64: each drop target's bank
    first_target: int  # element id of the first drop target
    max_multiplier: int
    save_frames: int  # how long a ball save lasts [frames] (0: no ball save)


def _padded(rows: list[list[int]]) -> np.ndarray:
    width = max([len(row) for row in rows] + [1])
    array = np.full((len(rows), width), -1, dtype=np.int64)
    for i, row in enumerate(rows):
        array[i, : len(row)] = row
    return array


def element_ids(table: Table, names: tuple[str, ...]) -> list[int]:
    """The element ids of ``names`` (a wall's name stands for each of its segments)."""
    ids = {name: i for i, name in enumerate(table.element_names)}
    out: list[int] = []
    for name in names:
        if name in ids:
            out.append(ids[name])
        else:
            out += [i for i, full in enumerate(table.element_names) if full.startswith(f"{name}[")]
    return out


class _Names(NamedTuple):
    """The names a table's rules refer to, in the order of the ids the compiled rules use."""

    lights: list[str]
    counters: list[str]
    timers: list[str]
    banks: list[str]
    kickbacks: list[str]
    locks: list[str]

    @classmethod
    def of(cls, table: Table) -> "_Names":
        rules = table.rules
        return cls(
            lights=[x.name for x in rules.lights] if rules else [],
            counters=list(rules.counters) if rules else [],
            timers=[x.name for x in rules.timers] if rules else [],
            banks=[bank.name for bank in table.drop_targets],
            kickbacks=[k.name for k in table.kickbacks],
            locks=[lock.name for lock in table.locks],
        )


def _trigger_row(table: Table, when: Trigger, names: _Names) -> tuple[int, int, int, list[int]]:
    """A trigger as the compiled rules read it: its kind, its bank, counter or timer (-1: none),
    its count and its ids (elements, lights or flippers)."""
    of_kind = {"bank": names.banks, "counter": names.counters, "timer_ends": names.timers}
    arg = of_kind[when.kind].index(when.names[0]) if when.kind in of_kind else -1
    if when.kind in ("hit", "locked"):
        ids = element_ids(table, when.names)
    elif when.kind == "lights_on":
        ids = [names.lights.index(name) for name in when.names]
    elif when.kind == "flipper":
        button = when.names[0]
        ids = [j for j, f in enumerate(table.flippers) if button in ("any", f.button)]
    else:
        ids = []
    return TRIGGERS.index(when.kind), arg, when.at, ids


def _effect_row(effect: Effect, names: _Names, rate: float) -> tuple[int, int, int, list[int]]:
    """An effect as the compiled rules read it: its kind, its counter, timer, kickback or lock
    (-1: none), its value (a ball save's in frames) and the lights it acts on."""
    of_kind = {"count": names.counters, "start_timer": names.timers,
               "light_kickback": names.kickbacks, "release_lock": names.locks}  # fmt: skip
    target = of_kind[effect.kind].index(effect.names[0]) if effect.kind in of_kind else -1
    acted = [names.lights.index(n) for n in effect.names] if effect.kind in (
        "light", "unlight", "rotate") else []  # fmt: skip
    value = round(effect.value * rate) if effect.kind == "ball_save" else effect.value
    return EFFECTS.index(effect.kind), target, int(value), acted


def compile_rules(table: Table) -> RuleBook:
    """``table``'s rules and ball save as a :class:`RuleBook` (an inactive one without)."""
    rules = table.rules
    rate = table.simulation.frame_rate
    names = _Names.of(table)
    rule_list = rules.rules if rules else ()
    triggers = [_trigger_row(table, rule.when, names) for rule in rule_list]
    effects: list[tuple[int, int, int, list[int]]] = []
    starts = [0]  # rule r's effects are effects[starts[r]:starts[r + 1]]
    for rule in rule_list:
        effects += [_effect_row(effect, names, rate) for effect in rule.do]
        starts.append(len(effects))
    timer_rows = rules.timers if rules else ()
    guards = [-1 if r.if_lit is None else names.lights.index(r.if_lit) for r in rule_list]
    return RuleBook(
        active=rules is not None or table.ball_save is not None,
        order=np.array(rules.order() if rules else (), dtype=np.int64),
        trigger_kind=np.array([t[0] for t in triggers], dtype=np.int64),
        trigger_arg=np.array([t[1] for t in triggers], dtype=np.int64),
        trigger_at=np.array([t[2] for t in triggers], dtype=np.int64),
        trigger_ids=_padded([t[3] for t in triggers]),
        guard=np.array(guards, dtype=np.int64),
        effect_start=np.array(starts, dtype=np.int64),
        effect_kind=np.array([e[0] for e in effects], dtype=np.int64),
        effect_arg=np.array([e[1] for e in effects], dtype=np.int64),
        effect_value=np.array([e[2] for e in effects], dtype=np.int64),
        effect_lights=_padded([e[3] for e in effects]),
        timer_frames=np.array([max(1, round(x.time * rate)) for x in timer_rows], dtype=np.int64),
        timer_factor=np.array([x.factor for x in timer_rows], dtype=np.int64),
        timer_ids=_padded([element_ids(table, x.elements) for x in timer_rows]),
        target_bank=np.array(
            [b for b, bank in enumerate(table.drop_targets) for _ in bank.targets], dtype=np.int64
        ),
        first_target=table.element_names.index(table.drop_target_list[0].name)
        if table.drop_target_list
        else len(table.element_names),
        max_multiplier=rules.max_multiplier if rules else 1,
        save_frames=round(table.ball_save.time * rate) if table.ball_save else 0,
    )


@njit(cache=True)
def run_rules(env, book, state, scores):
    """Play the rules for env ``env`` after a frame's physics (its hits in ``state.world``,
    points per element id in ``scores``): the modes' extra points, then every rule whose
    trigger happened, in ``book.order``, as often as it happened. Returns the points the rules
    scored in the frame (the hits' own points are the caller's).

    The triggers are tested here rather than in a helper per rule: numba counts a reference to
    each array taken out of ``state`` for its env, and taking them out once per rule made the
    call about 6x slower (measured)."""
    hits = state.world.hits[env]
    lights, counters = state.lights[env], state.counters[env]
    events, were_on = state.rule_events[env], state.lights_were_on[env]
    commands, before = state.world.flipper_command[env], state.flippers_before[env]
    points, ended = run_timers(book, state.timers[env], hits, scores)
    for rule in book.order:
        kind, arg, ids = book.trigger_kind[rule], book.trigger_arg[rule], book.trigger_ids[rule]
        times = 0
        if kind in (HIT, LOCKED):
            for e in ids:
                if e >= 0:
                    times += hits[e]
        elif kind == BANK:
            struck, standing = False, False
            up = state.world.targets_up[env]
            for j in range(book.target_bank.shape[0]):
                if book.target_bank[j] == arg:
                    struck = struck or hits[book.first_target + j] > 0
                    standing = standing or up[j]
            times = 1 if struck and not standing else 0
        elif kind == FLIPPER:
            for j in ids:
                if j >= 0 and commands[j] and not before[j]:
                    times = 1
        elif kind == TIMER_ENDS:
            times = (ended >> arg) & 1
        elif kind == LIGHTS_ON:
            on = True
            for light in ids:
                if light >= 0 and not lights[light]:
                    on = False
            times = 1 if on and not were_on[rule] else 0
            were_on[rule] = on
        elif kind == MULTIBALL_STARTS:
            times = state.multiball_events[env, 0]
        elif kind == MULTIBALL_ENDS:
            times = state.multiball_events[env, 1]
        else:  # COUNTER
            times = counters[arg] // book.trigger_at[rule]
            counters[arg] -= times * book.trigger_at[rule]
        guard = book.guard[rule]
        if guard >= 0 and not lights[guard]:
            times = 0  # (if_lit) its light is out
        for _ in range(times):
            points += apply_effects(env, book, state, rule)
            events[rule] += 1
    for j in range(before.shape[0]):  # (an element loop: the step runs without NRT)
        before[j] = commands[j]
    state.rule_points[env] += points
    return points


# Inlined into run_rules (as compiled before it was split in two): no call per frame or rule.
@njit(cache=True, inline="always")
def run_timers(book, timers, hits, scores):
    """One frame of the running timers (one env's ``timers``, counting down): returns the extra
    points of the elements they multiply, hit in the frame, and the timers that ran out in it
    as bits (bit t: timer t)."""
    points = 0
    ended = 0
    for t in range(timers.shape[0]):
        if timers[t] > 0:
            factor = book.timer_factor[t]
            for e in book.timer_ids[t]:
                if e >= 0 and factor > 1:
                    points += hits[e] * scores[e] * (factor - 1)
            timers[t] -= 1
            if timers[t] == 0:
                ended |= 1 << t
    return points, ended


@njit(cache=True)
def apply_effects(env, book, state, rule):
    """Apply rule ``rule``'s effects in env ``env``; returns the points they score now."""
    lights, counters = state.lights[env], state.counters[env]
    points = 0
    for x in range(book.effect_start[rule], book.effect_start[rule + 1]):
        kind, arg, value = book.effect_kind[x], book.effect_arg[x], book.effect_value[x]
        acted = book.effect_lights[x]
        if kind in (LIGHT, UNLIGHT):
            for light in acted:
                if light >= 0:
                    lights[light] = kind == LIGHT
        elif kind == ROTATE:
            n = 0
            while n < acted.shape[0] and acted[n] >= 0:
                n += 1
            last = lights[acted[n - 1]]
            for i in range(n - 1, 0, -1):
                lights[acted[i]] = lights[acted[i - 1]]
            lights[acted[0]] = last
        elif kind == COUNT:
            counters[arg] += value
        elif kind == START_TIMER:
            state.timers[env, arg] = book.timer_frames[arg]
        elif kind == SCORE:
            points += value
        elif kind == BONUS:
            state.bonus[env] += value
        elif kind == MULTIPLIER:
            state.multiplier[env] = min(state.multiplier[env] + value, book.max_multiplier)
        elif kind == LIGHT_KICKBACK:
            state.world.kickback_lit[env, arg] = True
        elif kind == EXTRA_BALL:
            state.balls_left[env] += value
        elif kind == RELEASE_LOCK:  # Python lets them go (game.multiball) before the next frame
            state.lock_release[env, arg] = True
        elif kind == ADD_BALLS:
            state.pending_balls[env] += value
        else:  # BALL_SAVE
            state.multiball_save[env] = max(state.multiball_save[env], value)
    return points


@njit(cache=True)
def end_of_ball(env, book, state, tilted):
    """A ball of env ``env`` has left play: returns -1 when the ball save serves it again (it
    drained within the save's time, not on a tilt), else the end-of-ball bonus, the bonus
    times the multiplier (0 on a tilt; counted in ``state.rule_points``), after which both
    start again. The event is counted in ``state.rule_events`` (after the rules' columns)."""
    n_rules = book.trigger_kind.shape[0]
    if state.save_frames[env] > 0 and not tilted:
        state.save_frames[env] = 0  # once per ball
        state.rule_events[env, n_rules] += 1
        return -1
    award = 0 if tilted else state.bonus[env] * state.multiplier[env]
    if award > 0:
        state.rule_events[env, n_rules + 1] += 1
    state.rule_points[env] += award
    state.bonus[env] = 0
    state.multiplier[env] = 1
    state.save_frames[env] = -1  # the next ball's save starts at its launch
    return award
