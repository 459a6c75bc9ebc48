"""The cross-check's report: its headline figures and findings in words, each computed from the
measured rows of :mod:`.scenarios`, and its tables on the terminal."""

from typing import Any

from pinball_env.tools.crosscheck.scenarios import (
    CABINET_TABLE,
    DROP_TIME_TOLERANCE,
    ENGINES,
    FLIPPER_SPEED_TOLERANCE,
    FRAME_RATE,
    LOW_SPEED,
    ROUNDING,
    SUBSTEP,
    agrees,
    nudge_agrees,
    pair_agrees,
    plunger_agrees,
)


def headline_figures(report: dict[str, Any]) -> dict[str, Any]:
    """Agreement counts on the low-speed scenarios and the headline differences."""
    low = [row for row in report["wall_bounces"] if row["speed"] <= LOW_SPEED]
    tunnel = report["tunnelling"]
    first_pymunk_miss = {
        target: next(
            (v for v, f in zip(tunnel["speeds"], tunnel[target]["pymunk"], strict=True) if f > 0),
            None,
        )
        for target in ("wall", "resting flipper", "swinging flipper")
    }
    static = {
        "wall bounces at <= 4 m/s": low,
        "corner hits": report["corner_hits"],
        "post hits": report["post_hits"],
        "bumper hits": report["bumper_hits"],
    }
    shares = {name: {e: _share(rows, e) for e in ENGINES} for name, rows in static.items()}
    return {
        "findings": _findings(report, shares, first_pymunk_miss),
        "first_pymunk_pass_through_m_per_s": first_pymunk_miss,
        "low_speed_wall_bounces_within_tolerance": {e: _share(low, e) for e in ENGINES},
        "corner_hits_within_tolerance": {e: _share(report["corner_hits"], e) for e in ENGINES},
        "post_hits_within_tolerance": {e: _share(report["post_hits"], e) for e in ENGINES},
        "bumper_hits_within_tolerance": {e: _share(report["bumper_hits"], e) for e in ENGINES},
        "flipper_drop_max_relative_speed_difference": max(
            row["relative_speed_difference"] for row in report["flipper_drop"]
        ),
        "flipper_swing_max_relative_difference": max(
            row["relative_difference"] for row in report["flipper_swing"]
        ),
        "max_pass_through": {
            target: {e: max(tunnel[target][e]) for e in ENGINES}
            for target in ("wall", "resting flipper", "swinging flipper")
        },
        "free_run_diverges_1cm_at_s": report["free_run"]["diverges_1cm_at"],
        **_cabinet_figures(report),
    }


def _cabinet_figures(report: dict[str, Any]) -> dict[str, Any]:
    """The headline figures of the cabinet's scenarios: nudges, the plunger, the tilt."""
    plunger = report["plunger"]

    def apart(key: str) -> float:
        return max(abs(r["swept"][key] - r["pymunk"][key]) for r in plunger if r[key] is not None)

    contact: dict[str, dict[str, float]] = {}
    for row in report["nudge_contact"]:
        contact.setdefault(row["situation"], {})[row["nudge"]] = row["difference"]
    return {
        "tilted_bumper_hits_within_tolerance": {
            e: _share(report["tilted_bumper_hits"], e) for e in ENGINES
        },
        "nudge_free_flight_max_velocity_error_m_per_s": {
            e: max(row[e]["max_velocity_error"] for row in report["nudge_free_flight"])
            for e in ENGINES
        },
        "nudge_contact_velocity_difference_m_per_s": contact,
        "nudge_contact_as_predicted": all(nudge_agrees(row) for row in report["nudge_contact"]),
        "plunger_within_tolerance": {
            e: sum(plunger_agrees(row, e) for row in plunger) / len(plunger) for e in ENGINES
        },
        "plunger_max_apex_difference_m": apart("apex"),
        "plunger_max_gate_time_difference_s": apart("gate_time"),
        **_targets_figures(report),
    }


def _targets_figures(report: dict[str, Any]) -> dict[str, Any]:
    """The headline figures of the targets' scenarios."""
    drops = report["drop_target"]
    return {
        "drop_target_bounces_within_tolerance": {
            e: sum(agrees(row, e, row["speed"]) for row in drops) / len(drops) for e in ENGINES
        },
        "drop_target_falls_and_lets_through": {
            e: all(row[e]["fell"] and row[e]["passed_when_down"] for row in drops) for e in ENGINES
        },
        "spinner_revolutions": {e: [row[e] for row in report["spinner"]] for e in ENGINES},
        **_balls_figures(report),
    }


def _balls_figures(report: dict[str, Any]) -> dict[str, Any]:
    """The headline figures of the ball-ball scenarios."""
    pairs, cradle = report["ball_ball"], report["two_balls_cradled"]
    return {
        "ball_ball_within_tolerance": {
            e: sum(pair_agrees(row, e) for row in pairs) / len(pairs) for e in ENGINES
        },
        "ball_ball_max_velocity_error_m_per_s": {
            e: max(row[e]["velocity_error"] for row in pairs) for e in ENGINES
        },
        "ball_ball_max_contact_time_error_s": {
            e: max(abs(row[e]["contact_time_error"]) for row in pairs) for e in ENGINES
        },
        "two_balls_cradled_gap_m": {e: cradle[e]["gap"] for e in ENGINES},
        "two_balls_cradled_least_gap_m": {e: cradle[e]["least_gap"] for e in ENGINES},
        "two_balls_cradled_apart_m": cradle["apart"],
    }


def _share(rows: list, engine: str) -> float:
    """Share of the scenario ``rows`` in which ``engine`` agrees with the analytic answer."""
    return sum(agrees(row, engine, row["speed"]) for row in rows) / len(rows)


def _findings(
    report: dict[str, Any], shares: dict[str, dict[str, float]], first_pymunk_miss: dict
) -> list[str]:
    """The findings in words, each computed from the measured results."""
    static_agree = all(value == 1.0 for both in shares.values() for value in both.values())
    drops = report["flipper_drop"]
    drop_agree = all(
        0.0 <= row["time_difference"] <= DROP_TIME_TOLERANCE + 1e-9
        and row["relative_speed_difference"] <= FLIPPER_SPEED_TOLERANCE
        for row in drops
    )
    swing_worst = max(row["relative_difference"] for row in report["flipper_swing"])
    tunnel = report["tunnelling"]
    ours_through = max(max(tunnel[t]["swept"]) for t in first_pymunk_miss)
    g_h = abs(report["free_run"]["gravity"]) * SUBSTEP
    drift = report["free_run"]["divergence"][10]
    return [
        f"{'Agree' if static_agree else 'DISAGREE'}: share of shots within tolerance of the "
        f"analytic bounce, per engine: {shares}; pymunk sees a contact up to one substep late.",
        f"{'Agree' if drop_agree else 'DISAGREE'}: a ball dropped on a resting flipper lands "
        f"up to {1e3 * max(row['time_difference'] for row in drops):.2f} ms later in pymunk "
        "(one substep from its integration order, one from detection) and bounces within "
        f"{100 * max(row['relative_speed_difference'] for row in drops):.1f}% of our speed.",
        f"{'Agree' if swing_worst <= FLIPPER_SPEED_TOLERANCE else 'DISAGREE'}: a swinging flipper "
        f"launches a resting ball at speeds within {100 * swing_worst:.1f}% of each other "
        f"(tolerance {100 * FLIPPER_SPEED_TOLERANCE:.0f}%).",
        "Differ, by design: Chipmunk integrates positions before velocities, we integrate "
        "velocities first, so in free flight the paths differ by g h t: after 11 frames "
        f"measured {1e3 * drift:.3f} mm, predicted {1e3 * g_h * 11 / FRAME_RATE:.3f} mm.",
        "Differ, pymunk wrong: without continuous collision a fast ball passes through; first "
        f"pass-throughs at {first_pymunk_miss['wall']} m/s (wall), "
        f"{first_pymunk_miss['resting flipper']} m/s (resting flipper), "
        f"{first_pymunk_miss['swinging flipper']} m/s (swinging flipper). Ours: "
        f"{100 * ours_through:.0f}% at worst over all speeds.",
        "Free run: the paths drift apart by g h t until the first contact, where the "
        "one-substep detection delay separates them by "
        f"1 cm at {report['free_run']['diverges_1cm_at']} s; from there it is chaotic.",
        *_cabinet_findings(report),
    ]


def _cabinet_findings(report: dict[str, Any]) -> list[str]:
    """The cabinet's findings in words, each computed from the measured results."""
    summary = _cabinet_figures(report)
    tilted = summary["tilted_bumper_hits_within_tolerance"]
    flight = summary["nudge_free_flight_max_velocity_error_m_per_s"]
    walls = [row for row in report["nudge_contact"] if "expected_difference" in row]
    along = max(row["difference"] for row in walls if row["expected_difference"] == 0.0)
    into = max(row["difference"] for row in walls if row["expected_difference"] > 0.0)
    cradle = max(row["difference"] for row in report["nudge_contact"] if "bound" in row)
    plunger = summary["plunger_within_tolerance"]
    return [
        f"{'Agree' if min(tilted.values()) == 1.0 else 'DISAGREE'}: a tilted machine's bumpers "
        f"do not kick; share of shots within tolerance of the plain bounce: {tilted}.",
        f"{'Agree' if max(flight.values()) <= ROUNDING else 'DISAGREE'}: a nudge changes the "
        "velocity of a ball in free flight by the cabinet's change, opposite, to "
        f"{flight['swept']:.1e} m/s (swept) and {flight['pymunk']:.1e} m/s (pymunk).",
        f"{'Agree' if along <= ROUNDING else 'DISAGREE'}: a nudge along a wall on a ball resting "
        f"on it or rolling along it: the engines' velocities differ by {along:.1e} m/s (the "
        "same friction on the same normal impulse).",
        f"{'Differ, by design' if summary['nudge_contact_as_predicted'] else 'DISAGREE'}: a "
        "nudge into a surface is an impact for ours and a push for pymunk (which fixes a "
        "contact's bounce before the substep's velocity change): a ball on a wall leaves "
        f"{into:.3f} m/s faster in ours, e (J/M + g h); in a raised flipper's cradle the "
        f"engines end up to {cradle:.3f} m/s apart.",
        f"{'Agree' if min(plunger.values()) == 1.0 else 'DISAGREE'}: plunger launches on "
        f"{CABINET_TABLE} reach apexes {1e3 * summary['plunger_max_apex_difference_m']:.2f} mm "
        "apart (v h, the integration order) and cross the gate "
        f"{1e3 * summary['plunger_max_gate_time_difference_s']:.2f} ms apart; share within "
        f"tolerance of the analytic flight: {plunger}.",
        *_balls_findings(report),
    ]


def _balls_findings(report: dict[str, Any]) -> list[str]:
    """The ball-ball findings in words, each computed from the measured results."""
    figures = _balls_figures(report)
    share, error = (
        figures["ball_ball_within_tolerance"],
        figures["ball_ball_max_velocity_error_m_per_s"],
    )
    late = figures["ball_ball_max_contact_time_error_s"]
    cradle = report["two_balls_cradled"]
    least = figures["two_balls_cradled_least_gap_m"]
    resting = all(all(cradle[e]["in_play"]) and max(cradle[e]["speeds"]) < 0.01 for e in ENGINES)
    return [
        f"{'Agree' if min(share.values()) == 1.0 else 'DISAGREE'}: ball-ball shots (head-on, "
        "onto a resting ball, oblique at 45 deg; restitution 1 and 0.5) against the analytic "
        f"answer: share within tolerance {share}; largest velocity error {error['swept']:.1e} "
        f"m/s (swept), {error['pymunk']:.3f} m/s (pymunk: a substep late, its line of centres "
        f"turned by the overlap); implied contact time off by {1e6 * late['swept']:.1f} us "
        f"(swept) and {1e3 * late['pymunk']:.2f} ms (pymunk).",
        f"{'Agree' if resting and least['swept'] >= 0.0 else 'DISAGREE'}: two balls cradled on "
        f"a raised flipper come to rest touching, {1e6 * cradle['swept']['gap']:.2f} um apart "
        f"(swept, never closer than {1e6 * least['swept']:.2f} um) and "
        f"{1e6 * cradle['pymunk']['gap']:.2f} um (pymunk, which lets a resting contact overlap "
        f"up to its slop); the engines' rest positions {1e6 * cradle['apart']:.1f} um apart.",
    ]


def print_report(report: dict[str, Any]) -> None:
    """The report as tables on the terminal, then the summary."""
    _print_bounces(report)
    _print_flippers(report)
    _print_cabinet(report)
    print("\nDrop target shot straight at, at speed: bounce error [% of speed], fell, then passed")
    for row in report["drop_target"]:
        cells = "   ".join(
            f"{e} {100 * row[e]['relative_velocity_error']:6.3f} {row[e]['fell']!s:5} "
            f"{row[e]['passed_when_down']!s:5}"
            for e in ENGINES
        )
        print(f"  {row['speed']:4.1f} m/s: {cells}")
    print("\nBall-ball shots: velocity error [m/s] and implied contact time error [ms] per engine")
    for row in report["ball_ball"]:
        cells = "   ".join(
            f"{e} {row[e]['velocity_error']:.1e} {1e3 * row[e]['contact_time_error']:6.3f}"
            for e in ENGINES
        )
        print(f"  {row['shot']:>20} {row['speed']:3.1f} m/s e={row['restitution']:3.1f}: {cells}")
    print("\nSpinner passed once at speed: revolutions")
    for row in report["spinner"]:
        print(f"  {row['speed']:4.1f} m/s: " + "   ".join(f"{e} {row[e]:3d}" for e in ENGINES))
    free = report["free_run"]
    print(
        f"\nFree run on the classic table ({free['frames']} frames, plunger {free['launch_speed']}"
        f" m/s): paths differ by 1 mm after {free['diverges_1mm_at']} s, 1 cm after "
        f"{free['diverges_1cm_at']} s"
    )
    tunnel = report["tunnelling"]
    print(f"\nPass-through fraction ({tunnel['trials']} aimed shots per speed)")
    header = "".join(f"{speed:>8g}" for speed in tunnel["speeds"])
    print(f"{'target':>17} {'engine':>7} {header}  m/s")
    for target in ("wall", "resting flipper", "swinging flipper"):
        for engine in ENGINES:
            cells = "".join(f"{100 * f:7.0f}%" for f in tunnel[target][engine])
            print(f"{target:>17} {engine:>7} {cells}")
    print("\nSummary")
    for key, value in report["summary"].items():
        if key == "findings":
            for finding in value:
                print(f"  - {finding}")
        else:
            print(f"  {key}: {value}")


def _print_bounces(report: dict[str, Any]) -> None:
    """Wall bounces, corner, post and bumper hits against the analytic answer."""

    def fmt_time(value: float | None) -> str:
        return "  miss " if value is None else f"{1e3 * value:+6.2f}"

    print("Wall bounces: contact-time error [ms] and velocity error [% of speed] vs analytic")
    print(f"{'speed':>6} {'angle':>5} | {'swept dt':>8} {'dv%':>7} | {'pymunk dt':>9} {'dv%':>7}")
    for row in report["wall_bounces"]:
        s, p = row["swept"], row["pymunk"]
        through = " passed through" if p["passed_through"] else ""
        print(
            f"{row['speed']:6.1f} {row['angle']:5.0f} | {fmt_time(s['contact_time_error']):>8} "
            f"{100 * s['relative_velocity_error']:7.3f} | "
            f"{fmt_time(p['contact_time_error']):>9} {100 * p['relative_velocity_error']:7.3f}"
            f"{through}"
        )
    for name, key in (
        ("Corner hits", "offset"),
        ("Post hits", "offset"),
        ("Bumper hits", "offset"),
        ("Tilted bumper hits", "offset"),
    ):
        rows = report[name.lower().replace(" ", "_")]
        print(f"\n{name}: velocity error [% of speed] vs analytic")
        for row in rows:
            swept, pym = row["swept"], row["pymunk"]
            print(
                f"  {key} {row[key]:4.2f}: swept {100 * swept['relative_velocity_error']:7.3f}"
                f"   pymunk {100 * pym['relative_velocity_error']:7.3f}"
            )


def _print_flippers(report: dict[str, Any]) -> None:
    """The flipper drop and swing scenarios, engine against engine."""
    print("\nBall dropped on a resting flipper (with gravity)")
    for row in report["flipper_drop"]:
        t, v = row["contact_time"], row["bounce_speed"]
        print(
            f"  height {100 * row['height']:4.1f} cm: contact swept {1e3 * t['swept']:7.2f} ms "
            f"pymunk {1e3 * t['pymunk']:7.2f} ms; bounce swept {v['swept']:.3f} m/s "
            f"pymunk {v['pymunk']:.3f} m/s ({100 * row['relative_speed_difference']:.1f}%)"
        )
    print("\nSwinging flipper hits a resting ball")
    for row in report["flipper_swing"]:
        v = row["speed"]
        print(
            f"  {1e3 * row['along']:4.0f} mm from the pivot: swept {v['swept']:.3f} m/s, pymunk "
            f"{v['pymunk']:.3f} m/s ({100 * row['relative_difference']:.1f}%), "
            f"one-hit estimate (1+e) w r = {row['expected_about']:.3f} m/s"
        )


def _print_cabinet(report: dict[str, Any]) -> None:
    """The nudge and plunger scenarios: against the analytic answer, engine against engine."""

    def vector(v: list[float]) -> str:
        return f"({v[0]:+.4f}, {v[1]:+.4f})"

    print(
        f"\nNudge on a ball in free flight ({CABINET_TABLE}'s cabinet): max |ball dv + cabinet dv|"
    )
    for row in report["nudge_free_flight"]:
        errors = "   ".join(f"{e} {row[e]['max_velocity_error']:.1e} m/s" for e in ENGINES)
        print(f"  {row['nudge']:>11} over {row['frames']} frames: {errors}")
    print("\nNudge on a ball in contact: velocity [m/s] one frame after the shove")
    print(f"  {'situation':>21} {'nudge':>11} | {'swept':>18} {'pymunk':>18} | difference")
    for row in report["nudge_contact"]:
        v = row["velocity"]
        predicted = (
            f"(at most {row['bound']:.4f})"
            if "bound" in row
            else f"(predicted {row['expected_difference']:.4f})"
        )
        print(
            f"  {row['situation']:>21} {row['nudge']:>11} | {vector(v['swept'])} "
            f"{vector(v['pymunk'])} | {row['difference']:.4f} {predicted}"
        )
    print(f"\nPlunger launches on {CABINET_TABLE}: apex [m] or time to the gate [ms]")
    print(f"  {'pull':>4} {'speed':>5} | {'analytic':>9} {'swept':>9} {'pymunk':>9} | tolerance")
    for row in report["plunger"]:
        if row["apex"] is not None:
            key, scale, unit = "apex", 1.0, f"{row['apex_tolerance']:.5f} m"
        else:
            key, scale, unit = "gate_time", 1e3, f"{1e3 * row['gate_time_tolerance']:.3f} ms"
        values = [row[key]] + [row[e][key] for e in ENGINES]
        cells = " ".join(f"{scale * value:9.5f}" for value in values)
        print(f"  {row['pull']:4.2f} {row['speed']:5.3f} | {cells} | {unit}")
