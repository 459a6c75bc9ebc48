"""Which tables a game can be played on: :func:`check_playable` (one table), and
:func:`check_same_game` (another env's table in a game already made)."""

from pinball_env.table import TEST_TABLES, Table


def check_playable(table: Table) -> None:
    """A game needs a plunger to launch, flippers to play, an outline and a drain to end it: a
    ValueError names everything the table lacks."""
    lacks = [
        what
        for what, missing in (
            ("no plunger to launch the ball", table.plunger is None),
            ("no flippers to play", not table.flippers),
            ("no closed outline wall to keep the ball in", table.outline is None),
            ("no drain sensor to end a game", not any(s.drain for s in table.sensors)),
        )
        if missing
    ]
    if lacks:
        rig = " (it is a physics test rig)" if table.name in TEST_TABLES else ""
        raise ValueError(f"table {table.name!r} cannot be played{rig}: it has {', '.join(lacks)}")
    if not table.drain_reachable:
        raise ValueError(
            f"table {table.name!r}: no drain can be reached from the plunger, a game could "
            "never end"
        )


def check_same_game(table: Table, first: Table) -> None:
    """A playable ``table`` that an env of a game made on ``first`` can play: the step loop
    reads the ball, the simulation settings, the cabinet and the rules once per game, so they
    must be ``first``'s (a ValueError says which differ)."""
    check_playable(table)
    ball, simulation = table.ball, table.simulation
    if ball.radius != first.ball.radius or simulation != first.simulation:
        raise ValueError(
            f"table {table.name!r} has another ball size or simulation settings than "
            f"{first.name!r}: every env of a game needs the same"
        )
    # The step loop reads the cabinet's numbers, the player's plunger's among them, once.
    cabinet = (table.cabinet, table.tilt, table.plunger if table.has_cabinet else None)
    if cabinet != (first.cabinet, first.tilt, first.plunger if first.has_cabinet else None):
        raise ValueError(
            f"table {table.name!r} has another cabinet, tilt or player's plunger than "
            f"{first.name!r}: every env of a game needs the same"
        )
    # The rules are compiled once per game, on element ids.
    if (table.rules, table.ball_save) != (first.rules, first.ball_save) or (
        table.rules is not None and table.element_names != first.element_names
    ):
        raise ValueError(
            f"table {table.name!r} has other rules or ball save than {first.name!r}: "
            "every env of a game needs the same"
        )
