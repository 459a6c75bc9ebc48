"""A table's rules as data: lights, counters and timers, and rules that fire on a trigger and
apply their effects (the ``rules`` section of a table file; ``rules_schema`` validates it,
``game.rulebook`` plays it).

A rule is ``when`` (one trigger) and ``do`` (effects, in order):

- triggers: ``hit`` (any of the named elements hit: a sensor crossed, a target or bumper struck,
  a spinner's revolution, a kickback's line crossed), ``bank`` (a drop bank's last target
  falls), ``lights_on`` (the named lights become all lit), ``flipper`` (a flipper button,
  ``left``, ``right`` or ``any``, pressed), ``counter`` (a counter reaches ``at``; it then starts
  again from 0), ``timer_ends``, and for multiball ``locked`` (a ball is locked in the named
  lock), ``multiball_starts`` and ``multiball_ends`` (``true``: two or more balls came into
  play, one is left);
- effects: ``light``, ``unlight`` (lights), ``rotate`` (lights pass their states one place on,
  the last's to the first: a "lane change"), ``count`` (add ``by``, default 1, to a counter),
  ``start_timer`` (a timer runs for its ``time`` again; while it runs, the points of its
  ``elements`` are multiplied by its ``factor``), ``score`` (points now), ``bonus`` (points to
  the end-of-ball bonus), ``multiplier`` (raise the bonus multiplier, up to
  ``max_multiplier``), ``light_kickback``, ``extra_ball``, and for multiball ``release_lock``
  (the named lock lets its balls go), ``add_balls`` (the auto-plunger launches that many balls
  from the trough) and ``ball_save`` (seconds: a ball of those in play that drains meanwhile is
  launched again by the auto-plunger).

A rule with ``if_lit: LIGHT`` fires only while that light is lit (a jackpot lit during a
multiball: a ``multiball_starts`` rule lights it, a ``multiball_ends`` rule puts it out).

At the end of each ball the bonus times the multiplier is scored (nothing on a tilt), and both
start again (0 and x1); lights, counters and timers carry over to the next ball.

Rules fire in a frame after its physics: first those whose trigger is a physical event (hit,
bank, flipper, timer_ends), in file order, then those triggered by other rules (lights_on,
counter), each after every rule that could trigger it. A set of rules that could trigger each
other in a ring (and so could fire for ever within a frame) is refused (:func:`find_cycle`).
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Keyword:
    """A trigger or effect of a table file: what it names (the kind of name: elements, banks,
    lights, buttons, counters, timers or kickbacks, and whether a list is allowed; None: it takes
    a number instead) and what it means (the table reference shows it)."""

    names: tuple[str, bool] | None
    meaning: str


# The triggers and effects, in the order the error messages list them; the parser, the writer
# and the table reference all read these.
TRIGGER_KEYS: dict[str, Keyword] = {
    "hit": Keyword(
        ("elements", True),
        "any of the named elements is hit: a sensor crossed, a target or bumper struck, a "
        "spinner's revolution, a kickback's line crossed",
    ),
    "bank": Keyword(("banks", False), "the named drop bank's last target falls"),
    "flipper": Keyword(("buttons", False), "a flipper button (left, right or any) is pressed"),
    "timer_ends": Keyword(("timers", False), "the named timer runs out"),
    "lights_on": Keyword(("lights", True), "the named lights become all lit"),
    "counter": Keyword(
        ("counters", False), "the named counter reaches `at`; it then starts again from 0"
    ),
    "locked": Keyword(("locks", False), "a ball is locked in the named lock"),
    "multiball_starts": Keyword(
        None, "a multiball starts: a second ball comes into play (balls held in locks are not)"
    ),
    "multiball_ends": Keyword(None, "a multiball ends: one ball is left in play"),
}
EFFECT_KEYS: dict[str, Keyword] = {
    "light": Keyword(("lights", True), "light the named lights"),
    "unlight": Keyword(("lights", True), "put the named lights out"),
    "rotate": Keyword(
        ("lights", True),
        "the lights (at least two) pass their states one place on, the last's to the first "
        '(a "lane change")',
    ),
    "count": Keyword(("counters", False), "add `by` (default 1) to the named counter"),
    "start_timer": Keyword(
        ("timers", False),
        "the named timer runs for its time again; while it runs, the points of its elements "
        "are multiplied by its factor",
    ),
    "score": Keyword(None, "score this many points now"),
    "bonus": Keyword(None, "add this many points to the end-of-ball bonus"),
    "multiplier": Keyword(None, "raise the bonus multiplier by this much, up to max_multiplier"),
    "light_kickback": Keyword(("kickbacks", False), "light the named kickback"),
    "extra_ball": Keyword(None, "award this many extra balls"),
    "release_lock": Keyword(("locks", False), "the named lock lets its balls go at its kick"),
    "add_balls": Keyword(
        None,
        "the trough's auto-plunger launches this many more balls (as many as the trough holds), "
        "one at a time as the shooter lane clears",
    ),
    "ball_save": Keyword(
        None,
        "a ball save of this many seconds for the balls in play: a ball that drains meanwhile is "
        "launched again by the auto-plunger (a multiball's start)",
    ),
}
TRIGGERS = tuple(TRIGGER_KEYS)
EFFECTS = tuple(EFFECT_KEYS)
# Triggers set off by the physics or the player, and those set off by other rules' effects.
EVENT_TRIGGERS = ("hit", "bank", "flipper", "timer_ends", "locked", "multiball_starts",
                  "multiball_ends")  # fmt: skip
RULE_TRIGGERS = tuple(key for key in TRIGGERS if key not in EVENT_TRIGGERS)
FLIPPER_BUTTONS = ("left", "right", "any")
# What each trigger and effect names (see Keyword.names).
TRIGGER_NAMES = {key: keyword.names for key, keyword in TRIGGER_KEYS.items()}
EFFECT_NAMES = {key: keyword.names for key, keyword in EFFECT_KEYS.items()}
# Events that are no rule's but are reported with them (``info["rule_events"]``).
BALL_SAVED = "ball saved"
BONUS_SCORED = "end-of-ball bonus"


@dataclass(frozen=True)
class Light:
    """A lamp on the playfield that the rules light and put out."""

    name: str
    at: tuple[float, float]  # where it is drawn [m]
    lit: bool = False  # at the start of a game [-]


@dataclass(frozen=True)
class Timer:
    """A mode: while it runs, the points of ``elements`` are multiplied by ``factor``."""

    name: str
    time: float  # how long it runs once started [s]
    factor: int = 1  # [-]
    elements: tuple[str, ...] = ()  # element names (a wall's segments by the wall's name)


@dataclass(frozen=True)
class Trigger:
    """What fires a rule: ``kind`` (one of TRIGGERS) and the names it is about (elements,
    a bank, lights, a flipper button, a counter, a timer); ``at`` for a counter."""

    kind: str
    names: tuple[str, ...]
    at: int = 0


@dataclass(frozen=True)
class Effect:
    """What a rule does: ``kind`` (one of EFFECTS), the names it acts on (lights, a counter, a
    timer, a kickback) and its number (points, steps, balls)."""

    kind: str
    names: tuple[str, ...] = ()
    value: float = 0  # an int but for ball_save's seconds


@dataclass(frozen=True)
class Rule:
    """``do`` when ``when`` happens (only while light ``if_lit`` is lit, where it names one)."""

    name: str
    when: Trigger
    do: tuple[Effect, ...]
    if_lit: str | None = None


@dataclass(frozen=True)
class RuleSet:
    """The ``rules`` section of a table."""

    lights: tuple[Light, ...] = ()
    counters: tuple[str, ...] = ()
    timers: tuple[Timer, ...] = ()
    max_multiplier: int = 1  # the bonus multiplier's top [-]
    rules: tuple[Rule, ...] = ()

    @property
    def event_names(self) -> tuple[str, ...]:
        """Names of what ``info["rule_events"]`` counts: the rules, then the ball save and the
        end-of-ball bonus."""
        return (*(rule.name for rule in self.rules), BALL_SAVED, BONUS_SCORED)

    def triggers(self, effect: Effect, rule: Rule) -> bool:
        """Whether ``effect`` can set off ``rule``'s trigger within the same frame."""
        when = rule.when
        if when.kind == "lights_on":
            return effect.kind in ("light", "rotate") and bool(set(effect.names) & set(when.names))
        if when.kind == "counter":
            return effect.kind == "count" and effect.names == when.names
        return False

    def order(self) -> tuple[int, ...]:
        """The rules in the order they are run in a frame: event-triggered ones in file order,
        then the rest each after every rule that can trigger it (raises ValueError on a
        cycle, see :func:`find_cycle`)."""
        cycle = find_cycle(self)
        if cycle:
            raise ValueError(" -> ".join(repr(self.rules[i].name) for i in cycle))
        first = [i for i, rule in enumerate(self.rules) if rule.when.kind in EVENT_TRIGGERS]
        done: list[int] = []

        def visit(i: int) -> None:
            if i in done:
                return
            for j, other in enumerate(self.rules):
                if other.when.kind in RULE_TRIGGERS and any(
                    self.triggers(e, self.rules[i]) for e in other.do
                ):
                    visit(j)
            done.append(i)

        for i, rule in enumerate(self.rules):
            if rule.when.kind in RULE_TRIGGERS:
                visit(i)
        return (*first, *done)


def find_cycle(rules: RuleSet) -> list[int]:
    """Indices of rules that can trigger one another in a ring (the first's index repeated at
    the end), or [] when there is none. A rule's effect triggers another rule when it lights
    one of the lights that rule waits for all of, or counts on its counter."""
    edges = [
        [j for j, other in enumerate(rules.rules) if any(rules.triggers(e, other) for e in rule.do)]
        for rule in rules.rules
    ]
    state = [0] * len(edges)  # 0 new, 1 on the path, 2 done
    path: list[int] = []

    def walk(i: int) -> list[int]:
        state[i] = 1
        path.append(i)
        for j in edges[i]:
            if state[j] == 1:
                return [*path[path.index(j) :], j]
            if state[j] == 0:
                found = walk(j)
                if found:
                    return found
        path.pop()
        state[i] = 2
        return []

    for i in range(len(edges)):
        if state[i] == 0:
            found = walk(i)
            if found:
                return found
    return []
