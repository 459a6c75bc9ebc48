"""Table files written as a base plus what changes (``base:``): the built-in versions load to
exactly the tables their whole files gave, the merge's rules, and the errors of a bad base."""

import dataclasses
import subprocess
from pathlib import Path

import numpy as np
import pytest
import yaml

from pinball_env.recording import table_sha256
from pinball_env.table import (
    TableError,
    builtin_tables_dir,
    dump_table,
    load_table,
    table_description,
)
from pinball_env.table.fields import Where
from pinball_env.table.files import merge_description

ROOT = Path(__file__).resolve().parents[2]
# The commit whose built-in tables were whole files, and the digests of the tables they gave
# (recording.table_sha256: the canonical JSON of everything a table file describes).
WHOLE_FILES = "4c51a58"
DIGESTS = {
    "box": "17330adb8fcbc69b4a4cc92efaff45fe66a26c073cb1f7d0f4e530b612bab17d",
    "classic": "d241a4f7604a7adb10b96da539dfa50377cb221d0342f99e51d526fed9d7fb4a",
    "classic_v1": "8d340b383d403931426d2b903b0c2ccee872a52960c59dfbae255104bb8ebc45",
    "classic_v2": "37e18975611b6ab5b3569191a28b1c6bdffb4a4ad05f02ee5c9738376f7af470",
    "classic_v3": "da552841e9f431aac9e899c598cdb17aedb246e8eb3d1fe41a7d08d284defd1b",
}
VERSIONS = {"classic_v1": "classic", "classic_v2": "classic_v1", "classic_v3": "classic_v2"}


def whole_file(name: str) -> str | None:
    """The built-in table's file at WHOLE_FILES, or None outside a git checkout that has it."""
    try:
        out = subprocess.run(
            ["git", "show", f"{WHOLE_FILES}:pinball_env/table/tables/{name}.yaml"],
            cwd=ROOT, capture_output=True, text=True, timeout=60,
        )  # fmt: skip
    except (OSError, subprocess.SubprocessError):
        return None
    return out.stdout if out.returncode == 0 else None


@pytest.mark.parametrize("name", sorted(DIGESTS))
def test_a_builtin_table_is_the_table_its_whole_file_gave(name, tmp_path):
    table = load_table(name)
    assert table_sha256(table) == DIGESTS[name]
    text = whole_file(name)
    if text is None:
        pytest.skip(f"needs the git checkout with commit {WHOLE_FILES}")
    (tmp_path / f"{name}.yaml").write_text(text, encoding="utf-8")
    whole = load_table(tmp_path / f"{name}.yaml")
    assert dataclasses.replace(whole, source=table.source) == table
    for before, after in zip(whole.pack(), table.pack(), strict=True):
        np.testing.assert_array_equal(before, after)
        assert before.dtype == after.dtype
    np.testing.assert_array_equal(whole.element_scores, table.element_scores)
    np.testing.assert_array_equal(whole.pack_ball_pair(), table.pack_ball_pair())
    assert whole.pack_settings() == table.pack_settings()


@pytest.mark.parametrize(("name", "base"), VERSIONS.items())
def test_each_version_is_written_as_the_one_before_plus_what_changed(name, base):
    data = yaml.safe_load((builtin_tables_dir() / f"{name}.yaml").read_text(encoding="utf-8"))
    assert data["base"] == base
    # Nothing restated: every key but the name differs from the base's.
    before = table_description(base)
    assert all(data[key] != before.get(key) for key in data if key not in ("base", "name"))
    if name == "classic_v2":  # v1's but for two of the tilt's values
        assert data == {"base": base, "name": name, "tilt": {"ring_angle": 1.0, "settle_time": 1.0}}


@pytest.mark.parametrize("name", sorted(VERSIONS))
def test_a_version_writes_back_a_whole_file(name, tmp_path):
    table = load_table(name)
    path = dump_table(table, tmp_path / "again.yaml")
    data = yaml.safe_load(path.read_text(encoding="utf-8"))
    assert "base" not in data and set(table_description(name)) <= set(data)
    assert load_table(path) == dataclasses.replace(table, source=str(path))


# --- the merge ----------------------------------------------------------------------------------

HERE = Where("v.yaml")


def test_mappings_merge_key_by_key_and_null_removes_a_key():
    base = {"a": 1, "b": {"x": 1, "y": [1, 2]}, "c": 3}
    change = {"b": {"y": [3], "z": 4}, "c": None, "d": 5}
    merged = merge_description(base, change, HERE)
    assert merged == {"a": 1, "b": {"x": 1, "y": [3], "z": 4}, "d": 5}
    assert list(merged) == ["a", "b", "d"]  # the base's order, new keys after it
    assert base == {"a": 1, "b": {"x": 1, "y": [1, 2]}, "c": 3}  # nothing modified


def test_a_list_or_any_other_value_replaces_the_bases():
    base = {"sensors": [{"name": "a"}, {"name": "b"}], "ball": {"radius": 0.01}, "n": 1}
    change = {"sensors": [{"name": "b"}], "ball": 3, "n": {"x": 1}}
    assert merge_description(base, change, HERE) == change


def test_null_for_a_key_the_base_lacks_is_refused():
    with pytest.raises(TableError, match=r"^v\.yaml: b\.q: null removes a key of the base"):
        merge_description({"b": {"x": 1}}, {"b": {"q": None}}, HERE)


def test_the_merge_is_bounded():
    base = {"a": {"b": {"c": 1}}}
    with pytest.raises(TableError, match=r"v\.yaml: a\.b: more than \d+ values to merge"):
        merge_description(base, {"a": {"b": {"c": 2}}}, HERE, budget=[2])


# --- bases in files -----------------------------------------------------------------------------


def write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


def test_a_file_may_derive_from_a_builtin_table_or_a_file_beside_it(tmp_path):
    steeper = write(tmp_path / "steeper.yaml", "base: classic\nname: steeper\nslope_deg: 7.0\n")
    table = load_table(steeper)
    assert (table.name, table.slope_deg) == ("steeper", 7.0)
    assert dataclasses.replace(table, name="classic", slope_deg=6.5, source="") == (
        dataclasses.replace(load_table("classic"), source="")
    )
    (tmp_path / "sub").mkdir()
    heavier = write(tmp_path / "sub" / "heavier.yaml", "base: ../steeper.yaml\nball: {mass: 0.1}\n")
    table = load_table(heavier)
    assert (table.name, table.slope_deg, table.ball.mass) == ("steeper", 7.0, 0.1)
    assert table.source == str(heavier)


@pytest.mark.parametrize(
    ("base", "message"),
    [
        ("classic_v9", r"a\.yaml: base: unknown table 'classic_v9' \(available: classic, "),
        ("nowhere.yaml", r"a\.yaml: base: .*: table file not found"),
        ("3", r"a\.yaml: base: expected a table's name or path, got int 3"),
        ("a.yaml", r"a\.yaml: base: a ring of bases: a\.yaml -> a\.yaml"),
        ("b.yaml", r"b\.yaml: base: a ring of bases: a\.yaml -> b\.yaml -> a\.yaml"),
    ],
)
def test_a_bad_base_is_refused_naming_the_file_and_key(tmp_path, base, message):
    write(tmp_path / "b.yaml", "base: a.yaml\nname: b\n")
    path = write(tmp_path / "a.yaml", f"base: {base}\nname: a\n")
    with pytest.raises(TableError, match=message):
        load_table(path)


def test_a_version_is_checked_whole(tmp_path):
    path = write(tmp_path / "v.yaml", "base: classic\ntilt: {ring_angle: 1.0}\n")
    with pytest.raises(TableError, match=r"v\.yaml: tilt: missing required key 'bob_length'"):
        load_table(path)
