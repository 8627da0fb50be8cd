"""Units on variables: the YAML key, its errors, the round trip, and where units are shown."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import jsonschema
import numpy as np
import pytest
import yaml
from _codegen_util import CC, needs_cc, skip_no_cc

from fuzzkit.cli import main
from fuzzkit.codegen.emit import emit
from fuzzkit.codegen.table_search import make_table
from fuzzkit.codegen.toolchain import STRICT_FLAGS, run_compiler
from fuzzkit.codegen.verify import load_module
from fuzzkit.errors import RuleBaseError
from fuzzkit.formats.schema import json_schema
from fuzzkit.formats.yaml_reader import load_file, loads_rulebase
from fuzzkit.formats.yaml_writer import dump
from fuzzkit.fuzzy.inference import Engine
from fuzzkit.fuzzy.validation import check

DATA = Path(__file__).parent / "data"
TEMPERATURE = DATA / "temperature_pd.yaml"
TEXT = TEMPERATURE.read_text()


def _with_de_units(value: str) -> str:
    """The temperature rule base with ``de``'s ``units: K/s`` line replaced (line 13)."""
    assert "    units: K/s\n" in TEXT
    return TEXT.replace("    units: K/s\n", f"    units: {value}\n")


def test_units_are_read_per_variable() -> None:
    rb = load_file(TEMPERATURE)
    assert [(v.name, v.units) for v in rb.inputs + rb.outputs] == [
        ("e", "K"),
        ("de", "K/s"),
        ("heat", "%"),
    ]


def test_units_are_optional_and_null_means_none() -> None:
    without = TEXT.replace("    units: K/s\n", "")
    assert loads_rulebase(without).input("de").units is None
    assert loads_rulebase(_with_de_units("null")).input("de").units is None


@pytest.mark.parametrize("units", ["K/s", "%", "°C", "N·m", "mm s^-1", "yes", "1e-3", "*/"])
def test_units_round_trip_through_the_writer(units: str) -> None:
    rb = loads_rulebase(_with_de_units(json.dumps(units)))
    assert rb.input("de").units == units
    again = loads_rulebase(dump(rb))
    assert again == rb
    assert again.input("de").units == units


@pytest.mark.parametrize(
    "value, match",
    [
        ("3", r":13:12: expected the units of input 'de' as text .*got 3; quote it"),
        ("true", r":13:12: expected the units of input 'de' as text .*got true; quote it"),
        ("[K, s]", r":13:12: expected the units of input 'de' as text .*got a list"),
        ("{a: K}", r":13:12: expected the units of input 'de' as text .*got a mapping"),
        ("''", r":13:12: units of input 'de': expected a unit such as 'N'.*empty string"),
        ("' K'", r":13:12: units of input 'de': expected no leading or trailing spaces"),
        ('"K\\ts"', r":13:12: units of input 'de': expected printable characters on one line"),
        ('"K\\ns"', r":13:12: units of input 'de': expected printable characters on one line"),
        (
            "'" + "m" * 25 + "'",
            r":13:12: units of input 'de': expected at most 24 characters, got 25",
        ),
    ],
)
def test_bad_units_are_located_and_explained(value: str, match: str) -> None:
    with pytest.raises(RuleBaseError, match=match):
        loads_rulebase(_with_de_units(value), "temperature_pd.yaml")


def test_units_key_misspelt_gets_a_suggestion() -> None:
    text = TEXT.replace("    units: K/s\n", "    unit: K/s\n")
    with pytest.raises(RuleBaseError, match=r":13:5: unknown key 'unit'.*did you mean 'units'"):
        loads_rulebase(text)


def test_hand_built_model_with_bad_units_fails_validation() -> None:
    rb = load_file(TEMPERATURE)
    bad = dataclasses.replace(rb.outputs[0], units="a\nb")
    issues = check(dataclasses.replace(rb, outputs=(bad,)))
    assert [path for path, _ in issues] == [("outputs", "heat", "units")]


def test_json_schema_accepts_units_and_rejects_bad_ones() -> None:
    schema = json_schema()
    doc = yaml.safe_load(TEXT)
    jsonschema.validate(doc, schema)
    for bad in (3, "", " K", "m" * 25):
        doc["inputs"]["de"]["units"] = bad
        with pytest.raises(jsonschema.ValidationError):
            jsonschema.validate(doc, schema)


def test_info_shows_units(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["info", str(TEMPERATURE)]) == 0
    out = capsys.readouterr().out
    assert "  e  [-20, 20] K\n" in out
    assert "  de  [-2, 2] K/s\n" in out
    assert "  heat  [0, 100] %  default NaN\n" in out


HOSTILE = '"*/ ??/ \\"\\"\\" °C µm²"'


def _hostile_rulebase():  # type: ignore[no-untyped-def]
    return loads_rulebase(_with_de_units(HOSTILE))


def test_generated_banners_name_the_units_sanitised() -> None:
    # "*/" would end the C comment, "??/" is a trigraph, '"""' ends the docstring; non-ASCII
    # symbols are spelt out.
    rb = _hostile_rulebase()
    tab = make_table(rb, number_type="double", resolution=9)
    line = "Units: e [K], de [* / ? ?/ ''' degC um^2], heat [%]"
    header = emit(rb, tab, "c")["temperature_pd.h"]
    assert line in header
    assert "in[0]  e in [-20.0, 20.0] [K]" in header
    assert "out[0] heat in [0, 100] [%]" in header
    assert line in emit(rb, tab, "python")["temperature_pd.py"]


def test_generated_python_with_hostile_units_imports_and_matches_the_engine() -> None:
    rb = _hostile_rulebase()
    tab = make_table(rb, number_type="double", resolution=9)
    module = load_module(emit(rb, tab, "python"), rb.name)
    rng = np.random.default_rng(13)
    e, de = rng.uniform(-20, 20, 200), rng.uniform(-2, 2, 200)
    want = Engine(rb).evaluate({"e": e, "de": de})["heat"]
    got = np.array([module.eval((a, b))[0] for a, b in zip(e, de, strict=True)])
    assert np.max(np.abs(got - want)) <= tab.bound[0]


@needs_cc
@skip_no_cc
@pytest.mark.parametrize("number_type", ["double", "q15"])
def test_generated_c_with_hostile_units_compiles_strictly(tmp_path: Path, number_type: str) -> None:
    rb = _hostile_rulebase()
    tab = make_table(rb, number_type=number_type, resolution=9)  # type: ignore[arg-type]
    files = emit(rb, tab, "c")
    for rel, text in files.items():
        (tmp_path / rel).write_text(text)
    assert CC is not None
    srcs = [rel for rel in files if rel.endswith(".c")]
    proc = run_compiler([*CC, *STRICT_FLAGS, "-c", *srcs], tmp_path)
    assert proc.stderr.strip() == ""
