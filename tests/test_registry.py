"""Finding rule bases by shipped name or path, from the source tree and from a plain install."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

import fuzzkit
from fuzzkit.errors import RuleBaseError
from fuzzkit.formats.registry import available, load, loads

ROOT = Path(__file__).resolve().parent.parent
SHIPPED_FILES = sorted(p.stem for p in (ROOT / "rulebases").glob("*.yaml"))


def test_available_lists_every_shipped_yaml() -> None:
    assert available() == SHIPPED_FILES
    assert {"macvicar_whelan", "paper_table1", "gaussian5", "three_input"} <= set(available())


def test_load_by_name_and_by_path_give_equal_models(tmp_path: Path) -> None:
    by_name = load("macvicar_whelan")
    by_path = load(str(ROOT / "rulebases" / "macvicar_whelan.yaml"))
    by_pathlike = load(ROOT / "rulebases" / "macvicar_whelan.yaml")
    assert by_name == by_path == by_pathlike
    assert by_name.source is not None and by_name.source.path.endswith("macvicar_whelan.yaml")
    # A copy elsewhere, and one without a YAML suffix in the working folder.
    copy = tmp_path / "mine.yml"
    shutil.copy(ROOT / "rulebases" / "gaussian5.yaml", copy)
    assert load(str(copy)) == load("gaussian5")
    bare = tmp_path / "bare"
    shutil.copy(ROOT / "rulebases" / "gaussian5.yaml", bare)
    cwd = os.getcwd()
    try:
        os.chdir(tmp_path)
        assert load("bare") == load("gaussian5")
    finally:
        os.chdir(cwd)


def test_top_level_exports() -> None:
    assert fuzzkit.load("paper_table1") == load("paper_table1")
    assert fuzzkit.available() == available()
    assert fuzzkit.loads((ROOT / "rulebases" / "three_input.yaml").read_text()) == load(
        "three_input"
    )


def test_unknown_name_lists_available_names_and_suggests_one() -> None:
    with pytest.raises(RuleBaseError) as info:
        load("macvicar_whelen")
    message = str(info.value)
    assert "no shipped rule base or file called 'macvicar_whelen'" in message
    assert "(did you mean 'macvicar_whelan'?)" in message
    for name in SHIPPED_FILES:
        assert name in message


def test_missing_file_is_a_rule_base_error(tmp_path: Path) -> None:
    with pytest.raises(RuleBaseError, match=r"nope\.yaml: cannot read: No such file"):
        load(str(tmp_path / "nope.yaml"))
    with pytest.raises(RuleBaseError, match=r"is a directory"):
        load(str(tmp_path) + os.sep)


def test_loads_names_the_source_in_errors() -> None:
    with pytest.raises(RuleBaseError, match=r"^snippet:1:1: expected a rule base"):
        loads("[1, 2]\n", source="snippet")
