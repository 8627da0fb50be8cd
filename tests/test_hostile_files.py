"""Hostile files (issue 25): each class is refused at its ``file:line:col`` with exit 2, or
handled; what one command writes, the others read (or the writer refuses with the limit)."""

from __future__ import annotations

import re
import time
from pathlib import Path

import numpy as np
import pytest

import fuzzkit
from fuzzkit.cli import main
from fuzzkit.errors import RuleBaseError
from fuzzkit.formats import registry
from fuzzkit.fuzzy import resolution, validation
from fuzzkit.fuzzy.inference import evaluate
from fuzzkit.fuzzy.model import Compound, Proposition, Rule, RuleBase, Variable

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "docs" / "examples"
MW = (ROOT / "rulebases" / "macvicar_whelan.yaml").read_text()
HEATER = (EXAMPLES / "heater.fis").read_text()
FEED = (EXAMPLES / "feed.fll").read_text()
GRIPPER = (EXAMPLES / "gripper_iec.fcl").read_text()


def _refused(tmp_path: Path, name: str, text: str) -> RuleBaseError:
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(RuleBaseError) as info:
        registry.load(path)
    return info.value


def _line_col(text: str, needle: str) -> tuple[int, int]:
    at = text.index(needle)
    return text.count("\n", 0, at) + 1, at - (text.rfind("\n", 0, at) + 1) + 1


@pytest.mark.parametrize(
    "name, old, new, needle, match",
    [
        # integers too large for a float, and past Python's 4300-digit limit
        ("a.yaml", "range: [-1, 1]", "range: [-1, 1" + "0" * 320 + "]", "1000", "321 digits"),
        ("a.yaml", "range: [-1, 1]", "range: [-1, 1" + "0" * 5000 + "]", "1000", "5001 digits"),
        # a YAML control character (refused by the YAML reader, now with its place)
        ("a.yaml", "name: macvicar_whelan", "name: macvicar\x07_whelan", "\x07", "U+0007"),
        # .fis counts far beyond the file's content (formerly an endless loop)
        ("a.fis", "NumInputs=2", "NumInputs=100000000", "100000000", "[Input3] is missing"),
        ("a.fis", "NumMFs=3", "NumMFs=1000000000000000000", "[Input1]", "MF4 is missing"),
        ("a.fis", "NumRules=6", "NumRules=1e18", "[Rules]", "has 6 rule lines"),
        # an output range far wider than its terms, a subnormal range, a subnormal term edge
        ("a.fis", "Range=[0 100]", "Range=[0 1e14]", "MF1='off'", "below the engines' resolution"),
        ("a.fis", "Range=[-10 10]", "Range=[0 1e-310]", "[0 1e-310]", "too narrow to resolve"),
        ("a.fis", "[-5 0 5]", "[-5e-320 0 5e-320]", "MF2='zero'", "below the engines' resolution"),
        ("a.fis", "Range=[0 100]", "Range=[0 1e120]", "[0 1e120]", "reaches beyond"),
    ],
)
def test_hostile_rule_bases_are_refused_at_their_place(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    name: str,
    old: str,
    new: str,
    needle: str,
    match: str,
) -> None:
    base = MW if name.endswith(".yaml") else HEATER
    assert old in base
    text = base.replace(old, new, 1)
    start = time.perf_counter()
    err = _refused(tmp_path, name, text)
    assert time.perf_counter() - start < 5.0  # bounded work, not a loop over the counts
    hit = next((p for p in err.problems if match in p.message), None)
    assert hit is not None, [str(p) for p in err.problems]
    line, col = _line_col(text, needle)
    assert hit.location.line == line, str(hit)
    if name.endswith(".yaml"):
        assert hit.location.col == col, str(hit)
    # the command line: exit 2, the located message, no traceback or internal error
    assert main(["validate", str(tmp_path / name)]) == 2
    err = capsys.readouterr().err
    assert f"{tmp_path / name}:{line}:" in err and match in err
    assert "Traceback" not in err and "internal error" not in err


def test_truncated_fcl_term_is_located(tmp_path: Path) -> None:
    cut = GRIPPER[: GRIPPER.index(":=", GRIPPER.index("TERM")) + 2] + "\n"
    err = _refused(tmp_path, "a.fcl", cut)
    hit = next(p for p in err.problems if "expected a term after ':='" in p.message)
    line, col = _line_col(cut, "TERM none :=")
    assert (hit.location.line, hit.location.col) == (line, col + len("TERM none :=")), str(hit)


@pytest.mark.parametrize("name", ["a.fll", "a.fis"])
def test_a_rule_block_without_rules_is_refused_at_the_block(tmp_path: Path, name: str) -> None:
    if name.endswith(".fll"):
        text = "\n".join(ln for ln in FEED.split("\n") if not ln.strip().startswith("rule:"))
        block = "RuleBlock:"
    else:
        text = HEATER.replace("NumRules=6", "NumRules=0")
        text = text[: text.index("[Rules]") + 8]
        block = "[Rules]"
    err = _refused(tmp_path, name, text)
    (hit,) = err.problems
    assert "has no rules" in hit.message
    assert (hit.location.line, hit.location.col) == (_line_col(text, block)[0], 1)


def _heater_with_output_range(high: float) -> RuleBase:
    rb = registry.load(EXAMPLES / "heater.fis")
    out = rb.outputs[0]
    wide = Variable(out.name, 0.0, high, out.terms, out.default)
    return RuleBase(
        rb.name, rb.inputs, (wide,), rb.rules, rb.operators, rb.defuzzifier, rb.out_of_range
    )


@pytest.mark.parametrize("high", [1e14, 26.0 / resolution.RESOLUTION])
def test_an_output_range_too_wide_for_its_terms_is_refused(high: float) -> None:
    # the heater's output terms have features 25 apart: a range over 25 / RESOLUTION is refused
    issues = validation.check(_heater_with_output_range(high), allow_gaps=True)
    assert issues and all("below the engines' resolution" in m for _, m in issues)


@pytest.mark.filterwarnings("error")
def test_at_the_resolution_limit_the_engine_gives_finite_numbers() -> None:
    # the widest output range validation accepts for the heater's terms (25 apart) evaluates
    # to finite values at every input label peak, with no RuntimeWarning (warnings are errors)
    ok = _heater_with_output_range(24.0 / resolution.RESOLUTION)  # just inside the limit
    assert validation.check(ok, allow_gaps=True) == []
    e, d = np.meshgrid([-10.0, -5.0, 0.0, 5.0, 10.0], [-2.0, -0.5, 0.0, 0.5, 2.0])
    y = evaluate(ok, {"err": e.ravel(), "rate": d.ravel()})["power"]
    fired = ~np.isnan(y)
    assert fired.any() and np.all(np.isfinite(y[fired]))
    # the range only bounds the output: over the same terms, the heater's own answer
    own = evaluate(_heater_with_output_range(100.0), {"err": e.ravel(), "rate": d.ravel()})
    assert np.allclose(y, own["power"], rtol=0.0, atol=1e-9 * 100.0, equal_nan=True)


def test_cli_exit_2_and_nothing_written_for_a_long_name(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    src = tmp_path / "long.fis"
    src.write_text(HEATER.replace("Name='err'", "Name='" + "e" * 250_000 + "'"))
    out = tmp_path / "long.yaml"
    assert main(["import", str(src), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"{src}:15:6:" in err and "limited to 64 characters" in err and len(err) < 1000
    assert not out.exists()


def test_the_importer_refuses_yaml_its_reader_would_refuse(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # a 60 kB .fis of 4000 rules and 61-character names is 1.6 MB as YAML: over the limit
    names = ["v" * 60 + s for s in "12o"]
    labels = ["t" * 60 + str(i) for i in range(3)]
    mfs = [
        f"MF{i + 1}='{lab}':'trimf',[{i / 2 - 0.5} {i / 2} {i / 2 + 0.5}]"
        for i, lab in enumerate(labels)
    ]
    sections = [
        f"[{kind}]\nName='{name}'\nRange=[0 1]\nNumMFs=3\n" + "\n".join(mfs) + "\n"
        for kind, name in zip(("Input1", "Input2", "Output1"), names, strict=True)
    ]
    rules = [
        f"{1 + i % 3} {1 + i // 3 % 3}, {1 + i // 9 % 3} (1) : {1 + i // 27 % 2}"
        for i in range(4000)
    ]
    system = HEATER[: HEATER.index("[Input1]")].replace("NumRules=6", "NumRules=4000")
    src = tmp_path / "many.fis"
    src.write_text(system + "\n".join(sections) + "\n[Rules]\n" + "\n".join(rules) + "\n")
    out = tmp_path / "many.yaml"
    assert main(["import", str(src), "--out", str(out)]) == 2
    assert "limited to 1048576 bytes (1 MiB)" in capsys.readouterr().err
    assert not out.exists()


def _nested(depth: int) -> RuleBase:
    rb = registry.load("macvicar_whelan")
    expr: Compound | Proposition = Proposition("e", "NL")
    for i in range(depth):
        expr = Compound("and" if i % 2 else "or", (expr, Proposition("de", "NL")))
    first = Rule(expr, rb.rules[0].consequents)
    return RuleBase(rb.name, rb.inputs, rb.outputs, (first, *rb.rules[1:]), out_of_range="extend")


def test_deep_conditions_are_refused_by_every_writer_and_the_limit_round_trips(
    tmp_path: Path,
) -> None:
    deep = _nested(240)
    with pytest.raises(RuleBaseError, match=r"nested 240 and/or levels deep; .* limited to 32"):
        fuzzkit.dump(deep)
    for fmt in ("fll", "fcl", "fis"):
        with pytest.raises(RuleBaseError, match="limited to 32 levels"):
            registry.dumps(deep, fmt, allow_loss=True)
    at_limit = _nested(validation.MAX_CONDITION_DEPTH)
    for fmt in ("yaml", "fll", "fcl"):
        text = (
            fuzzkit.dump(at_limit)
            if fmt == "yaml"
            else registry.dumps(at_limit, fmt, allow_loss=True)
        )
        path = tmp_path / f"deep.{fmt}"
        path.write_text(text)
        again = registry.load(path)
        assert again.rules[0].antecedent == at_limit.rules[0].antecedent
        x = {"e": np.array([-1.0, 0.0, 1.0]), "de": np.array([-1.0, 0.0, 1.0])}
        assert np.allclose(evaluate(again, x)["du"], evaluate(at_limit, x)["du"], equal_nan=True)


def test_a_hand_written_yaml_condition_past_the_limit_is_located(tmp_path: Path) -> None:
    cond = "{e: NL}"
    for i in range(33):
        cond = f"{{{'and' if i % 2 else 'or'}: [{cond}, {{de: NL}}]}}"
    text = re.sub(r"rules:\n(.|\n)*", f"rules:\n  - {{if: {cond}, then: {{du: NL}}}}\n", MW)
    err = _refused(tmp_path, "deep.yaml", text)
    (hit,) = err.problems
    assert "limited to 32 levels" in hit.message and hit.location.line == text.count("\n")


@pytest.mark.filterwarnings("error")
def test_no_runtime_warning_reaches_the_user(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # refused before evaluating: a subnormal term edge (formerly NaN and a RuntimeWarning)
    sub = tmp_path / "sub.fis"
    sub.write_text(HEATER.replace("[-5 0 5]", "[-5e-320 0 5e-320]"))
    assert main(["eval", str(sub), "-i", "err=0", "-i", "rate=0"]) == 2
    # accepted at the resolution limit: evaluated without a warning (warnings are errors here)
    edge = tmp_path / "edge.yaml"
    edge.write_text(fuzzkit.dump(_heater_with_output_range(24.0 / resolution.RESOLUTION)))
    assert main(["eval", str(edge), "-i", "err=0", "-i", "rate=0", "--json"]) == 0
    out = capsys.readouterr()
    assert "Warning" not in out.err and re.search(r"\d", out.out)
