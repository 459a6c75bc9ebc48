"""The documentation's generated parts, written from the code's own declarations and the published
results so that they cannot drift: ``python docs/generate.py`` rewrites them, ``--check`` only
says which are stale (``tests/test_docs.py`` runs it).

A generated part sits in a page of ``docs/`` (or the README) between two markers::

    <!-- generated: NAME -->
    ...
    <!-- end generated: NAME -->

and ``NAME`` is one of :data:`GENERATORS` (``observation:Pinball-v1`` passes its argument on).
"""

from __future__ import annotations

import argparse
import ast
import dataclasses
import inspect
import itertools
import json
import re
import sys
import warnings
from collections.abc import Callable
from pathlib import Path

import gymnasium as gym
import yaml

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # the agents package, run from the checkout

from pinball_env.options import PinballOptions, VectorOptions  # noqa: E402
from pinball_env.protocol import PROTOCOL_ENV_IDS  # noqa: E402
from pinball_env.versions import (  # noqa: E402  (importing the package registers the envs)
    ENV_VERSIONS,
    EnvVersion,
    recordable_versions,
    version_history,
)

# The pages describe the older versions too, which Gymnasium calls out of date beside the newest.
warnings.filterwarnings("ignore", message=".*is out of date", category=DeprecationWarning)

PAGES = (ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")))
MARKER = re.compile(
    r"(<!-- generated: (?P<name>[\w:.-]+) -->\n)(?P<body>.*?)(<!-- end generated: (?P=name) -->)",
    re.S,
)
BENCHMARK = ROOT / "docs" / "benchmark.json"
CONFIGS = ROOT / "configs" / "agents"
DISTILL_CONFIGS = ROOT / "configs" / "distill"
PRETRAINED = ROOT / "agents" / "pretrained"


def _row(*cells: object) -> str:
    cells = tuple(str(cell).replace("|", "\\|").replace("\n", " ") for cell in cells)
    return "| " + " | ".join(cells) + " |"


def _table(header: tuple[str, ...], rows: list[tuple[object, ...]]) -> str:
    lines = [_row(*header), "|" + "---|" * len(header)]
    return "\n".join(lines + [_row(*row) for row in rows]) + "\n"


# --- the envs ------------------------------------------------------------------------------------


def _benchmark_role(version: EnvVersion) -> str:
    """An env's place in the benchmark protocol, in words."""
    if version.track is None:
        return "-"
    return "the protocol's env" if version.track == 0 else "a track"


def envs(_: str = "") -> str:
    """The registered envs (their version records): id, table, spaces, benchmark role and what
    each is."""
    rows = []
    for version in ENV_VERSIONS.values():
        env = gym.make(version.id)
        rows.append((f"`{version.id}`", f"`{version.table}`", f"`{env.action_space}`",
                     f"`{env.observation_space.shape}`", _benchmark_role(version),
                     version.summary))  # fmt: skip
        env.close()
    header = ("id", "table", "actions", "state observation", "benchmark", "what it is")
    return _table(header, rows)


def version_history_list(_: str = "") -> str:
    """The version history, from the version records: each env's name together, newest
    first."""
    return "".join(f"- **{v.id}**: {v.history}\n" for v in version_history())


def recordable_envs(_: str = "") -> str:
    """The envs the play tool plays and records, each with its own table; the default (the
    protocol's env) said."""
    named = [
        f"`{v.id}` (the default, on `{v.table}`)" if v.id == PROTOCOL_ENV_IDS[0]
        else f"`{v.id}` (on `{v.table}`)"
        for v in recordable_versions()
    ]  # fmt: skip
    return ", ".join(named[:-1]) + f" or {named[-1]}.\n"


def actions(env_id: str) -> str:
    """An env's discrete actions, by number, and its buttons (``action_type="multibinary"``)."""
    env = gym.make(env_id)
    meanings = env.unwrapped.get_action_meanings()
    buttons = env.unwrapped.game.button_names
    env.close()
    rows = [(number, f"`{name}`") for number, name in enumerate(meanings)]
    text = _table(("action", "name"), rows)
    listed = ", ".join(f"`{name}`" for name in buttons)
    kind = f'`action_type="multibinary"`: `MultiBinary({len(buttons)})`'
    return text + f"\n{kind}, the buttons {listed} in that order.\n"


def observation(env_id: str) -> str:
    """An env's state observation, row by row, with its bounds."""
    env = gym.make(env_id)
    rows = env.unwrapped.observation_rows
    env.close()
    return _table(
        ("index", "observation", "min", "max", "unit"),
        [(i, row.meaning, f"{row.low:.4g}", f"{row.high:.4g}", row.unit or "-")
         for i, row in enumerate(rows)],
    )  # fmt: skip


def _field_docs(cls: type, inherited: bool = False) -> dict[str, str]:
    """The docstring under each field of dataclass ``cls`` (its source's string after it); with
    ``inherited``, its bases' fields' too."""
    docs = {}
    if inherited:
        for base in reversed(cls.__mro__[1:]):
            if dataclasses.is_dataclass(base):
                docs.update(_field_docs(base))
    body = ast.parse(inspect.getsource(cls)).body[0].body  # type: ignore[attr-defined]
    for node, after in itertools.pairwise(body):
        documented = isinstance(after, ast.Expr) and isinstance(after.value, ast.Constant)
        if isinstance(node, ast.AnnAssign) and documented and isinstance(after.value.value, str):
            docs[node.target.id] = " ".join(after.value.value.split())  # type: ignore[union-attr]
    return docs


def _options_table(cls: type) -> str:
    docs = _field_docs(cls)
    rows = []
    for spec in dataclasses.fields(cls):
        default = getattr(spec.default, "value", spec.default)  # (an enum's value)
        rows.append((f"`{spec.name}`", f"`{default!r}`", docs[spec.name]))
    return _table(("option", "default", "meaning"), rows)


def options(_: str = "") -> str:
    """Every option of a game (``PinballOptions``), with its default and meaning."""
    return _options_table(PinballOptions)


def vector_options(_: str = "") -> str:
    """The options a vector env adds (``VectorOptions``)."""
    return _options_table(VectorOptions)


# --- tables --------------------------------------------------------------------------------------


def table_schema(_: str = "") -> str:
    """Every field of a table file, with its kind and range (the schema's declarations)."""
    from pinball_env.table.reference import schema_fields

    return _table(
        ("field", "value", "default"),
        [(f"`{f.path}`", f.kind, f"`{f.default}`" if f.default is not None else "required")
         for f in schema_fields()],
    )  # fmt: skip


def rules_schema(_: str = "") -> str:
    """The rules' triggers and effects (the rules' declarations)."""
    from pinball_env.table.reference import rule_keys

    return _table(("kind", "key", "what it does"), [(k.kind, f"`{k.key}`", k.meaning)
                                                    for k in rule_keys()])  # fmt: skip


# --- agents and results --------------------------------------------------------------------------


def _training(config: object, rllib: bool) -> str:
    """What a config trains on, in a few words: its envs, observation and training aids."""
    env = config.env  # type: ignore[attr-defined]
    options = env.kwargs
    words = [f"{env.num_envs} envs" + (" per runner" if rllib else "")]
    if options.get("obs_type", "state") != "state":
        words.append(
            f"{options['obs_type']} images"
            + (f" x{env.frame_stack}" if env.frame_stack > 1 else "")
        )
    if getattr(config, "imitation_steps", 0):
        words.append(f"warm start {config.imitation_steps / 1e6:g}M steps")  # type: ignore[attr-defined]
    if getattr(config, "kl_anchor_coef", 0):
        words.append(f"KL anchor {config.kl_anchor_coef:g}")  # type: ignore[attr-defined]
    for key, label in (
        ("repeat_action_probability", "sticky"),
        ("frame_skip", "frame skip"),
        ("skip_above", "skip above"),
        ("drain_penalty", "drain penalty"),
        ("height_shaping", "height shaping"),
        ("bonus_shaping", "bonus shaping"),
    ):
        if options.get(key):
            words.append(f"{label} {options[key]:g}")
    if options.get("nudge_actions") is False:
        words.append("no nudges")
    if env.normalize:
        words.append("VecNormalize")
    if getattr(config, "validate_every", 0):
        words.append("validation games")
    return ", ".join(words)


def configs(_: str = "") -> str:
    """Every training config in ``configs/agents/``: algorithm, env, budget, the benchmark's
    methods that train it, and what it trains on."""
    from agents.benchmark.methods import METHODS
    from agents.config import RllibConfig, TrainConfig, load_config
    from agents.distill import load_distill_config

    rows = []
    for path in sorted(CONFIGS.glob("*.yaml")):
        rllib = "env_runners" in yaml.safe_load(path.read_text())  # (agents.rllib's)
        # (unchecked: its checks need its libraries, Ray for RLlib's, which the docs need not)
        config = load_config(path, kind=RllibConfig if rllib else TrainConfig, check=False)
        algorithm = config.algo.upper() + (" (RLlib)" if rllib else "")
        frames = getattr(config, "total_frames", 0)
        budget = (
            f"{frames / 1e6:g}M frames" if frames else f"{config.total_timesteps / 1e6:g}M steps"
        )
        methods = ", ".join(name for name, m in METHODS.items() if m.config == path.name) or "-"
        rows.append((f"`{path.name}`", algorithm, f"`{config.env.id}`", budget, methods,
                     _training(config, rllib)))  # fmt: skip
    for path in sorted(DISTILL_CONFIGS.glob("*.yaml")):  # (agents.distill's)
        distilled = load_distill_config(path)
        budget = f"{distilled.iterations} x {distilled.env.num_envs} games"
        methods = ", ".join(name for name, m in METHODS.items() if m.config == path.name) or "-"
        rows.append((f"`distill/{path.name}`", "DAgger from the planner", f"`{distilled.env.id}`",
                     budget, methods, _training(distilled.learner(), False)))  # fmt: skip
    return _table(("config", "algorithm", "env", "budget", "benchmark methods", "trains on"), rows)


def config_keys(_: str = "") -> str:
    """Every key of a training config, with its default and meaning (``agents.config``)."""
    from agents.config import EnvConfig, RllibConfig, TrainConfig

    rows = []
    for prefix, cls, note in (("", TrainConfig, ""), ("", RllibConfig, "(RLlib) "),
                              ("env.", EnvConfig, "")):  # fmt: skip
        docs = _field_docs(cls, inherited=cls is not RllibConfig)  # (RLlib's own keys only)
        for spec in dataclasses.fields(cls):
            if spec.name in docs:
                default = spec.default
                if default is dataclasses.MISSING:
                    default = spec.default_factory()  # type: ignore[misc]
                rows.append((f"`{prefix}{spec.name}`", f"`{default!r}`", note + docs[spec.name]))
    return _table(("key", "default", "meaning"), rows)


def pretrained(_: str = "") -> str:
    """The agents that ship (``pretrained:NAME``), from their cards."""
    rows = []
    for path in sorted(PRETRAINED.glob("*.json")):
        card = json.loads(path.read_text())
        result = card["protocol"]
        low, high = result["score_iqm_ci95"]
        rows.append((f"`pretrained:{card['name']}`", f"`{card['env_id']}`",
                     f"`{card['config']}`", f"{card['trained']['frames'] / 1e6:.0f}M",
                     f"{result['score_iqm']:.0f} [{low:.0f}, {high:.0f}]",
                     card["chosen_by"]))  # fmt: skip
    return _table(("name", "env", "config", "frames", "IQM score [95% CI]", "chosen by"), rows)


def results(env_id: str = "") -> str:
    """The benchmark's table (``docs/benchmark.json``), for one env or all."""
    from agents.benchmark.tables import markdown_table

    published = json.loads(BENCHMARK.read_text())
    methods = {name: result for name, result in published["methods"].items()
               if not env_id or result["env_id"] == env_id}  # fmt: skip
    return markdown_table(methods)


def curves(env_id: str = "") -> str:
    """The learning curves' table (``docs/benchmark.json``'s validations), for one env or all."""
    from agents.benchmark.curves import curves_table

    published = json.loads(BENCHMARK.read_text())
    methods = {name: result for name, result in published["methods"].items()
               if not env_id or result["env_id"] == env_id}  # fmt: skip
    return curves_table(methods)


def references(_: str = "") -> str:
    """The protocol's reference scores (random and heuristic) per env."""
    published = json.loads(BENCHMARK.read_text())
    scores = published["protocol"]["reference_scores"]
    return _table(("env", "random", "heuristic"), [(f"`{env}`", f"{s['random']:.1f}",
                                                   f"{s['heuristic']:.1f}")
                                                  for env, s in scores.items()])  # fmt: skip


GENERATORS: dict[str, Callable[[str], str]] = {
    "envs": envs,
    "version-history": version_history_list,
    "recordable-envs": recordable_envs,
    "actions": actions,
    "observation": observation,
    "options": options,
    "vector-options": vector_options,
    "table-schema": table_schema,
    "rules-schema": rules_schema,
    "configs": configs,
    "config-keys": config_keys,
    "pretrained": pretrained,
    "results": results,
    "curves": curves,
    "references": references,
}


def generated(name: str) -> str:
    """The text of the generated part ``NAME`` (or ``NAME:ARGUMENT``)."""
    key, _, argument = name.partition(":")
    if key not in GENERATORS:
        raise SystemExit(f"unknown generated part {name!r} (known: {', '.join(GENERATORS)})")
    return GENERATORS[key](argument)


def regenerate(text: str, errors: list[str] | None = None) -> str:
    """``text`` with every generated part written anew. With ``errors``, a part that cannot be
    generated keeps its text and its error is added there; without, it raises."""

    def part(match: re.Match[str]) -> str:
        try:
            return match[1] + generated(match["name"]) + match[4]
        except Exception as error:
            if errors is None:
                raise
            errors.append(f"{match['name']}: {type(error).__name__}: {error}")
            return match[0]

    return MARKER.sub(part, text)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true", help="only list the stale pages")
    args = parser.parse_args(argv)
    stale, errors = [], []
    for page in PAGES:
        text = page.read_text()
        new = regenerate(text, errors)
        if new != text:
            stale.append(page.relative_to(ROOT))
            if not args.check:
                page.write_text(new)
    verb = "stale (run python docs/generate.py)" if args.check else "rewritten"
    for page in stale:
        print(f"{page}: {verb}")
    for error in errors:
        print(f"cannot generate {error}", file=sys.stderr)
    return 1 if errors or (args.check and stale) else 0


if __name__ == "__main__":
    raise SystemExit(main())
