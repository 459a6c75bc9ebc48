"""The element kinds, declared once: per kind its key (the ``Table`` field and the table file's
key), its class, its keys and their parsers, its limit and checks, its place in the element-id
order, how it is written back and what the renderer and the web page draw of it.

What reads it:

- parsing: ``schema.parse_elements`` parses each kind from its :attr:`ElementKind.fields`, with
  its limit and its checks, and ``schema.TABLE_FIELDS`` declares the kinds' keys by group;
- writing back: ``serialise.table_to_dict`` writes each kind's elements;
- element ids: :data:`ID_ORDER`, ``Table.element_names``, ``Table.element_scores`` and
  ``Table.element_ids``; ``rules_schema.rule_names``, the names the rules may use;
- drawing: :func:`static_shapes`, the static layer that ``render.Renderer`` paints and that the
  web page's geometry (``tools.web.stream.geometry``) sends. The moving parts (flippers, the drop
  targets standing or fallen, the spinners' flaps, the kickbacks' lamps) are drawn from the state
  by the renderer and the page themselves.

The kernel numbers the packed kinds in the same order with its ``first_*`` functions
(``physics.data``), which cannot read this registry (the physics imports nothing above it): the
tests hold the two together (``tests/table/test_kinds.py``).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass
from functools import partial
from typing import TYPE_CHECKING, Any, NamedTuple

from pinball_env.table import elements as el
from pinball_env.table.fields import Parser, Where, records
from pinball_env.table.parts import (
    DropBank,
    Flipper,
    Kickback,
    Lock,
    Post,
    Saucer,
    Sensor,
    Spinner,
    StandupTarget,
    Wall,
)

if TYPE_CHECKING:  # (the model reads this registry)
    from pinball_env.table.model import Table


class Line(NamedTuple):
    """A line of the static layer: its ends (x0, y0, x1, y1) [m] and its style (``"wall"``,
    ``"one_sided"``, ``"kicker"``, ``"sensor"``, ``"drain"`` or ``"target"``), which gives its
    colour and width."""

    segment: tuple[float, float, float, float]
    style: str


class Disc(NamedTuple):
    """A disc of the static layer: its centre and radius [m] and its style (``"post"``,
    ``"kicker"``, ``"drain"`` or ``"sensor"``), which gives its colour."""

    center: tuple[float, float]
    radius: float
    style: str


Shape = Line | Disc


def _one_id(element: Any) -> tuple[tuple[str, int], ...]:
    return ((element.name, element.score),)


def _itself(element: Any) -> tuple[Any, ...]:
    return (element,)


@dataclass(frozen=True)
class ElementKind:
    """One kind of element and everything the package needs to know of it."""

    key: str  # the Table field holding a tuple of them, and the table file's key
    model: type  # the class of one element
    fields: Mapping[str, Parser]  # its keys in file order and their parsers (POINT unbound)
    most: int  # at most this many in a table
    # Where its keys sit in a file: "core" (the first tables' elements, written even where a
    # table has none, so that those tables write and digest as they always did), "targets" or
    # "multiball" (written only where a table has some).
    group: str
    id_rank: int  # its place in the element-id order (0: its ids come first)
    # Whether Table.pack puts it in the kernel's arrays; the rest (played by sim.World) have
    # ids after every packed kind's.
    packed: bool = True
    check: Callable[[Any, Where], None] | None = None  # an element's checks beyond its keys
    check_all: Callable[[tuple[Any, ...], Where], None] | None = None  # the group's, as a whole
    # The (name, points per hit) of each of an element's ids, in order.
    ids: Callable[[Any], tuple[tuple[str, int], ...]] = _one_id
    # The named things of an element that the rules may name (a drop bank's: its targets).
    members: Callable[[Any], tuple[Any, ...]] = _itself
    # Its shapes in the static layer ((element, table) -> shapes); None: drawn from the state.
    draws: Callable[[Any, Table], Iterable[Shape]] | None = None
    layer: int = 1  # the static layer paints layer 0 (the floor's lines) under layer 1

    @property
    def declaration(self) -> Parser:
        """The declaration of the file's list of them (``schema.TABLE_FIELDS``'s entry)."""
        return partial(records, self.model, parsers=self.fields, max_len=self.most)

    @property
    def written_when_none(self) -> bool:
        """Whether a table without any writes the key (as an empty list)."""
        return self.group == "core"


def _wall_ids(wall: Wall) -> tuple[tuple[str, int], ...]:
    """A wall has an id per segment, named ``wall[i]``."""
    return tuple((f"{wall.name}[{i}]", wall.score) for i in range(len(wall.segments())))


def _wall_lines(wall: Wall, table: Table) -> Iterator[Line]:
    style = "one_sided" if wall.one_sided else "kicker" if wall.kick > 0 else "wall"
    return (Line(segment, style) for segment in wall.segments())


def _post_disc(post: Post, table: Table) -> tuple[Disc]:
    return (Disc(post.center, post.radius, "kicker" if post.kick > 0 else "post"),)


def _sensor_line(sensor: Sensor, table: Table) -> tuple[Line]:
    return (Line(sensor.segment, "drain" if sensor.drain else "sensor"),)


def _line_of(style: str, element: Any, table: Table) -> tuple[Line]:
    return (Line(element.segment, style),)


def _saucer_hole(saucer: Saucer, table: Table) -> tuple[Disc]:
    return (Disc(saucer.center, saucer.radius, "drain"),)


def _lock_holes(lock: Lock, table: Table) -> tuple[Disc, ...]:
    """A hole per slot, a little wider than a ball."""
    return tuple(Disc(slot, 1.2 * table.ball.radius, "sensor") for slot in lock.slots)


# The kinds in file order (as a file lists them, the parser parses and the writer writes them).
KINDS: tuple[ElementKind, ...] = (
    ElementKind("walls", Wall, el.WALL_FIELDS, el.MAX_SEGMENTS, "core", 0,
                check=el.check_wall, ids=_wall_ids, draws=_wall_lines),
    ElementKind("posts", Post, el.POST_FIELDS, el.MAX_POSTS, "core", 2, draws=_post_disc),
    ElementKind("flippers", Flipper, el.FLIPPER_FIELDS, el.MAX_FLIPPERS, "core", 3,
                check=el.check_flipper),
    ElementKind("sensors", Sensor, el.SENSOR_FIELDS, el.MAX_SENSORS, "core", 4,
                check=el.check_sensor, draws=_sensor_line, layer=0),
    ElementKind("standup_targets", StandupTarget, el.STANDUP_FIELDS, el.MAX_SEGMENTS,
                "targets", 1, draws=partial(_line_of, "target")),
    ElementKind("drop_targets", DropBank, el.DROP_BANK_FIELDS, el.MAX_DROP_TARGETS, "targets", 5,
                check_all=el.check_drop_target_count,
                ids=lambda bank: tuple((t.name, t.score) for t in bank.targets),
                members=lambda bank: bank.targets),
    ElementKind("spinners", Spinner, el.SPINNER_FIELDS, el.MAX_SPINNERS, "targets", 6,
                draws=partial(_line_of, "sensor")),
    ElementKind("kickbacks", Kickback, el.KICKBACK_FIELDS, el.MAX_KICKBACKS, "targets", 7,
                check=el.check_kickback, draws=partial(_line_of, "sensor")),
    ElementKind("saucers", Saucer, el.SAUCER_FIELDS, el.MAX_SAUCERS, "multiball", 8,
                packed=False, draws=_saucer_hole),
    ElementKind("locks", Lock, el.LOCK_FIELDS, el.MAX_LOCKS, "multiball", 9, packed=False,
                draws=_lock_holes),
)  # fmt: skip
KINDS_BY_KEY: dict[str, ElementKind] = {kind.key: kind for kind in KINDS}
# The element-id order: the walls' segments and the stand-up targets (the kernel's segments),
# posts (circles), flippers, sensors, drop targets, spinners, kickbacks, then the saucers and
# locks that Table.pack leaves out, so that no id of a table without them moves.
ID_ORDER: tuple[ElementKind, ...] = tuple(sorted(KINDS, key=lambda kind: kind.id_rank))
# The static layer's order: the floor's lines (layer 0) first, then the rest in file order.
DRAW_ORDER: tuple[ElementKind, ...] = tuple(
    sorted((kind for kind in KINDS if kind.draws is not None), key=lambda kind: kind.layer)
)


def kinds_of(group: str) -> tuple[ElementKind, ...]:
    """The kinds of a group (``"core"``, ``"targets"``, ``"multiball"``), in file order."""
    return tuple(kind for kind in KINDS if kind.group == group)


def element_ids(elements: Mapping[str, tuple[Any, ...]]) -> dict[str, range]:
    """Each kind's element ids, by key, for a table's element groups (``Table`` fields by key)."""
    ranges, first = {}, 0
    for kind in ID_ORDER:
        count = sum(len(kind.ids(element)) for element in elements.get(kind.key, ()))
        ranges[kind.key] = range(first, first + count)
        first += count
    return ranges


def static_shapes(table: Table) -> Iterator[Shape]:
    """The table's static layer, in the order it is painted (:data:`DRAW_ORDER`)."""
    for kind in DRAW_ORDER:
        draws = kind.draws
        assert draws is not None  # (DRAW_ORDER holds the kinds that draw)
        for element in getattr(table, kind.key):
            yield from draws(element, table)
