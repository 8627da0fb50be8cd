"""The spec's ``surface:`` and ``inputs:`` sections: reading, writing, schema, role mapping."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import jsonschema
import pytest
import yaml

from fuzzkit.control.spec import EXACT, Surface, surface_inputs
from fuzzkit.control.spec_reader import loads_spec
from fuzzkit.control.spec_schema import json_schema
from fuzzkit.control.spec_writer import dump_spec
from fuzzkit.errors import ConfigError, ControllerSpecError

ROOT = Path(__file__).resolve().parent.parent
FUZZY_TEXT = (ROOT / "docs" / "examples" / "controller.yaml").read_text(encoding="utf-8")
PI_TEXT = (ROOT / "docs" / "examples" / "controller_pi.yaml").read_text(encoding="utf-8")


def _with(extra: str, base: str = FUZZY_TEXT) -> str:
    return base.rstrip("\n") + "\n" + extra


@pytest.mark.parametrize(
    ("extra", "surface", "inputs"),
    [
        ("", EXACT, None),
        ("surface: exact\n", EXACT, None),
        ("surface: {method: exact}\n", EXACT, None),
        ("inputs: [e, de]\n", EXACT, ("e", "de")),
        ("inputs: [de, e]\n", EXACT, ("de", "e")),
    ],
)
def test_surface_and_inputs_are_read_and_written_back(
    extra: str, surface: Surface, inputs: tuple[str, str] | None
) -> None:
    spec = loads_spec(_with(extra), "spec.yaml")
    assert (spec.surface, spec.inputs) == (surface, inputs)
    again = loads_spec(dump_spec(spec), "again.yaml")
    assert (again.surface, again.inputs) == (surface, inputs)
    assert again.axes == spec.axes


def test_roles_follow_the_mapping_else_the_position() -> None:
    spec = loads_spec(FUZZY_TEXT, "spec.yaml")
    assert spec.rulebase is not None
    assert spec.rulebase.input_names == ("e", "de")
    assert surface_inputs(spec, spec.rulebase) == (0, 1)
    swapped = loads_spec(_with("inputs: [de, e]\n"), "spec.yaml")
    assert surface_inputs(swapped, spec.rulebase) == (1, 0)
    from dataclasses import replace

    with pytest.raises(ConfigError, match="'x' is not an input of rule base"):
        surface_inputs(replace(spec, inputs=("x", "de")), spec.rulebase)


@pytest.mark.parametrize(
    ("extra", "needle", "match"),
    [
        ("surface: tabel\n", "tabel", "unknown surface method 'tabel'; expected exact or table"),
        ("surface: {method: table}\n", "{method", "needs exactly one of tolerance"),
        (
            "surface: {method: table, tolerance: 0.001, resolution: 65}\n",
            "{method",
            "needs exactly one of tolerance",
        ),
        ("surface: {method: table, tolerance: 2}\n", "2}", r"tolerance is a fraction .* \(0, 1\)"),
        ("surface: {method: table, tolerance: .nan}\n", ".nan", "tolerance is a fraction"),
        ("surface: {method: table, resolution: 1}\n", "1}", "expected an integer >= 2"),
        ("surface: {method: exact, tolerance: 0.1}\n", "{method", "exact surface takes no"),
        ("surface: {method: table, tol: 0.1}\n", "tol:", "unknown key 'tol' in surface"),
        ("surface: [exact]\n", "[exact]", "expected a surface method"),
        ("inputs: [e, x]\n", "[e, x]", "change input 'x' is not an input of rule base"),
        ("inputs: [e, e]\n", "[e, e]", "must differ"),
        ("inputs: [e, de, du]\n", "[e, de, du]", "expected 2 input names"),
        ("inputs: e\n", "e\n", "expected inputs"),
    ],
)
def test_bad_surface_or_inputs_are_located(extra: str, needle: str, match: str) -> None:
    text = _with(extra)
    with pytest.raises(ControllerSpecError) as info:
        loads_spec(text, "spec.yaml")
    hits = [p for p in info.value.problems if re.search(match, p.message)]
    assert hits, [str(p) for p in info.value.problems]
    line = text.count("\n", 0, text.rindex(extra)) + 1
    col = extra.index(needle.rstrip("\n")) + 1 if needle != "e\n" else len("inputs: ") + 1
    assert (hits[0].location.line, hits[0].location.col) == (line, col), str(hits[0])


@pytest.mark.parametrize(
    ("extra", "match"),
    [
        ("surface: {method: table, tolerance: 0.001}\n", "a pi controller has no surface"),
        ("inputs: [e, de]\n", "a pi controller has no rule base to map inputs of"),
    ],
)
def test_a_pi_takes_neither(extra: str, match: str) -> None:
    with pytest.raises(ControllerSpecError, match=match):
        loads_spec(_with(extra, PI_TEXT), "pi.yaml")
    assert loads_spec(_with("surface: exact\n", PI_TEXT), "pi.yaml").surface == EXACT


@pytest.mark.parametrize(
    ("extra", "surface"),
    [
        ("surface: {method: table, tolerance: 0.001}\n", Surface("table", tolerance=0.001)),
        ("surface: {method: table, resolution: 65}\n", Surface("table", resolution=65)),
    ],
)
def test_a_table_surface_is_read_and_written_back(extra: str, surface: Surface) -> None:
    spec = loads_spec(_with(extra), "spec.yaml")
    assert spec.surface == surface
    assert loads_spec(dump_spec(spec), "again.yaml").surface == surface


def test_validate_accepts_a_table_surface(tmp_path: Path) -> None:
    spec = tmp_path / "table.yaml"
    spec.write_text(_with("surface: {method: table, resolution: 65}\n"), encoding="utf-8")
    run = subprocess.run(
        [sys.executable, "-m", "fuzzkit", "validate", str(spec)],
        capture_output=True,
        text=True,
        check=False,
        cwd=ROOT,
    )
    assert run.returncode == 0, run.stdout + run.stderr
    assert f"{spec}: ok" in run.stdout


def test_schema_agrees_with_the_reader() -> None:
    validator = jsonschema.Draft202012Validator(json_schema())
    doc = yaml.safe_load(FUZZY_TEXT)
    good = [
        {"surface": "exact"},
        {"inputs": ["e", "de"]},
        {"surface": {"method": "table", "tolerance": 0.001}},
        {"surface": {"method": "table", "resolution": 65}},
    ]
    bad = [
        {"surface": "tabel"},
        {"surface": {"method": "table"}},
        {"surface": {"method": "table", "tolerance": 0.001, "resolution": 65}},
        {"surface": {"method": "table", "resolution": 1}},
        {"inputs": ["e"]},
        {"inputs": "e"},
    ]
    for extra in good:
        assert list(validator.iter_errors({**doc, **extra})) == [], extra
        loads_spec(yaml.safe_dump({**doc, **extra}), "spec.yaml")
    for extra in bad:
        assert list(validator.iter_errors({**doc, **extra})), extra
        with pytest.raises(ControllerSpecError):
            loads_spec(yaml.safe_dump({**doc, **extra}), "spec.yaml")
