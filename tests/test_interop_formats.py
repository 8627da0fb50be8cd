"""FIS, FCL and FLL import and export: exact mappings, lossless round trips, shipped examples."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from _fis_probe import fis_with_input_mf
from _random_rulebases import MATLAB_SHAPES, random_rulebase

from fuzzkit.formats import fcl, fis, fll
from fuzzkit.formats.foreign_common import ExportError
from fuzzkit.formats.registry import available, dumps, load
from fuzzkit.formats.yaml_reader import loads_rulebase
from fuzzkit.formats.yaml_writer import dump
from fuzzkit.fuzzy import membership
from fuzzkit.fuzzy.inference import evaluate
from fuzzkit.fuzzy.model import Compound, RuleBase, Term, Variable
from fuzzkit.fuzzy.type2_model import Type2RuleBase

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "docs" / "examples"
MAMDANI_EXAMPLES = ["heater.fis", "gripper_iec.fcl", "gripper_named.fcl", "feed.fll"]
SUGENO_EXAMPLES = ["heater_sugeno.fis", "feed_sugeno.fll"]
# the foreign formats hold type-1 systems: an interval type-2 rule base is refused on export
# (tests/test_type2_format.py), so the round trip covers the type-1 shipped rule bases
TYPE1_SHIPPED = [n for n in available() if not isinstance(load(n), Type2RuleBase)]


def _plain(rb: RuleBase) -> RuleBase:
    """What every format holds: no table layout hint, no source; imported systems always get
    ``coverage: allow_gaps`` (gaps are warnings, see fuzzkit.formats.foreign_common.finish)."""
    return replace(rb, table=None, source=None, coverage="allow_gaps")


def as_format_holds(rb: RuleBase, fmt: str) -> RuleBase:
    """``rb`` with what ``fmt`` cannot hold replaced by the format's meaning."""
    rb = _plain(rb)
    if fmt == "fis":
        outputs = tuple(replace(v, default=(v.low + v.high) / 2) for v in rb.outputs)
        order = {v.name: i for i, v in enumerate(rb.inputs)}
        rules = []
        for rule in rb.rules:  # a .fis rule lists its conditions in input order
            if isinstance(rule.antecedent, Compound):
                ops = sorted(rule.antecedent.operands, key=lambda p: order[p.variable])  # type: ignore[union-attr]
                rule = replace(rule, antecedent=replace(rule.antecedent, operands=tuple(ops)))
            rules.append(rule)
        return replace(
            rb, outputs=outputs, rules=tuple(rules), out_of_range="extend", description=""
        )
    if fmt in ("fcl", "fcl-iec"):
        return replace(rb, out_of_range="extend", description="")
    return replace(rb, description=" ".join(rb.description.split()))


def _write(rb: RuleBase, fmt: str) -> str:
    if fmt == "fcl-iec":
        return fcl.dumps(rb, dialect="iec", allow_loss=True)
    return dumps(rb, fmt, allow_loss=True)


def _read(text: str, fmt: str) -> RuleBase:
    return {"fis": fis.loads, "fcl": fcl.loads, "fcl-iec": fcl.loads, "fll": fll.loads}[fmt](text)


# ---------------------------------------------------------------------------- shape mappings

#: MATLAB's membership functions written from the Fuzzy Logic Toolbox documentation, with
#: MATLAB's parameter order, independently of fuzzkit.
MATLAB = {
    "gbellmf": lambda x, a, b, c: 1 / (1 + np.abs((x - c) / a) ** (2 * b)),
    "sigmf": lambda x, a, c: 1 / (1 + np.exp(-a * (x - c))),
    "gaussmf": lambda x, sigma, c: np.exp(-((x - c) ** 2) / (2 * sigma**2)),
    "trimf": lambda x, a, b, c: np.maximum(np.minimum((x - a) / (b - a), (c - x) / (c - b)), 0),
    "trapmf": lambda x, a, b, c, d: np.clip(np.minimum((x - a) / (b - a), (d - x) / (d - c)), 0, 1),
}


@pytest.mark.parametrize(
    "mf, params",
    [
        ("gbellmf", (0.7, 2.5, 0.3)),
        ("sigmf", (-3.0, 0.4)),
        ("gaussmf", (0.45, -0.2)),
        ("trimf", (-0.8, 0.1, 0.9)),
        ("trapmf", (-0.9, -0.2, 0.3, 0.7)),
    ],
)
def test_fis_membership_functions_keep_matlab_parameter_order(
    mf: str, params: tuple[float, ...]
) -> None:
    text = fis_with_input_mf(f"'{mf}',[{' '.join(map(str, params))}]")
    term = fis.loads(text).inputs[0].terms[1]
    x = np.linspace(-3, 3, 2001)  # beyond the range too: MATLAB does not clamp
    np.testing.assert_allclose(
        membership.evaluate_term(term, x), MATLAB[mf](x, *params), atol=1e-12
    )


def test_fis_trapmf_with_infinite_feet_is_a_shoulder_everywhere() -> None:
    rb = fis.loads(fis_with_input_mf("'trapmf',[-inf -inf -0.5 0.5]"))
    term = rb.inputs[0].terms[1]
    assert term.shape == "left_shoulder" and term.params == (-0.5, 0.5)
    x = np.array([-1e6, -0.5, 0.0, 0.5, 1e6])
    np.testing.assert_allclose(membership.evaluate_term(term, x), [1, 1, 0.5, 0, 0])
    assert "'trapmf',[-inf -inf -0.5 0.5]" in fis.dumps(rb)


@pytest.mark.parametrize(
    "fll_term, fcl_term, shape, params",
    [
        ("Bell 0.3 0.7 2.5", "gbell 0.7 2.5 0.3", "bell", (0.7, 2.5, 0.3)),
        ("Sigmoid 0.4 -3", "sigm -3 0.4", "sigmoid", (-3.0, 0.4)),
        ("Gaussian -0.2 0.45", "gauss -0.2 0.45", "gaussian", (-0.2, 0.45)),
        ("Ramp 0.5 -0.5", "(-0.5, 1) (0.5, 0)", "left_shoulder", (-0.5, 0.5)),
        ("Ramp -0.5 0.5", "(-0.5, 0) (0.5, 1)", "right_shoulder", (-0.5, 0.5)),
        ("Discrete -1 0 0 1 1 0", "(-1, 0) (0, 1) (1, 0)", "triangle", (-1.0, 0.0, 1.0)),
        ("Trapezoid -1 -0.5 0 1", "trape -1 -0.5 0 1", "trapezoid", (-1.0, -0.5, 0.0, 1.0)),
    ],
)
def test_fll_and_fcl_terms_map_to_the_same_fuzzkit_shape(
    fll_term: str, fcl_term: str, shape: str, params: tuple[float, ...]
) -> None:
    fll_text = f"""Engine: probe
InputVariable: x
  range: -1 1
  term: all Gaussian 0 1
  term: probe {fll_term}
OutputVariable: y
  range: 0 1
  aggregation: Maximum
  defuzzifier: Centroid 100
  term: a Triangle 0 0.5 1
RuleBlock: r
  rule: if x is all then y is a
"""
    fcl_text = f"""FUNCTION_BLOCK probe
VAR_INPUT x : REAL; END_VAR
VAR_OUTPUT y : REAL; END_VAR
FUZZIFY x
  RANGE := (-1 .. 1);
  TERM all := Gaussian 0 1;
  TERM probe := {fcl_term};
END_FUZZIFY
DEFUZZIFY y
  RANGE := (0 .. 1);
  TERM a := Triangle 0 0.5 1;
  METHOD : COG;
END_DEFUZZIFY
RULEBLOCK r
  RULE 1 : IF x IS all THEN y IS a;
END_RULEBLOCK
END_FUNCTION_BLOCK
"""
    for rb in (fll.loads(fll_text), fcl.loads(fcl_text)):
        term = rb.inputs[0].terms[1]
        assert (term.shape, term.params) == (shape, params)


# ---------------------------------------------------------------------------- examples


@pytest.mark.parametrize("name", MAMDANI_EXAMPLES)
def test_examples_import_evaluate_and_round_trip_through_every_format(name: str) -> None:
    rb = load(EXAMPLES / name)
    point = {v.name: np.linspace(v.low, v.high, 7) for v in rb.inputs}
    out = evaluate(rb, point)
    for var in rb.outputs:
        assert np.all((out[var.name] >= var.low) & (out[var.name] <= var.high))
    own = Path(name).suffix[1:]
    assert _read(_write(rb, own), own) == _plain(rb)


def test_the_two_fcl_dialects_of_the_gripper_are_one_rule_base() -> None:
    iec, named = load(EXAMPLES / "gripper_iec.fcl"), load(EXAMPLES / "gripper_named.fcl")
    assert _plain(iec) == _plain(named)
    assert [t.shape for t in iec.inputs[0].terms] == ["left_shoulder", "triangle", "right_shoulder"]


def test_heater_fis_rules_read_as_written() -> None:
    rb = load(EXAMPLES / "heater.fis")
    # "-1 3, 3 (0.5) : 1": if err is not neg and rate is rising then power is mid, weight 0.5
    last = rb.rules[-1]
    assert last.weight == 0.5 and last.consequents[0].term == "mid"
    props = last.antecedent.operands  # type: ignore[union-attr]
    assert [(p.variable, p.term, p.negated) for p in props] == [
        ("err", "neg", True),
        ("rate", "rising", False),
    ]
    assert rb.rules[4].antecedent.op == "or"  # type: ignore[union-attr]
    assert rb.out_of_range == "extend" and rb.outputs[0].default == 50.0


def test_fis_output_outside_the_range_uses_matlab_semantics() -> None:
    # MATLAB evaluates terms where the input is: far beyond the range 'pos' is still 1
    rb = load(EXAMPLES / "heater.fis")
    inside = evaluate(rb, {"err": 10.0, "rate": 0.0})["power"]
    beyond = evaluate(rb, {"err": 1e3, "rate": 0.0})["power"]
    assert beyond == pytest.approx(inside, abs=1e-9)
    rising = evaluate(rb, {"err": 0.0, "rate": 20.0})["power"]
    assert math.isfinite(float(rising))


@pytest.mark.parametrize("name", SUGENO_EXAMPLES)
def test_sugeno_examples_import_and_round_trip(name: str) -> None:
    rb = load(EXAMPLES / name)
    own = Path(name).suffix[1:]
    assert _read(_write(rb, own), own) == _plain(rb)


# ---------------------------------------------------------------------------- round trips


def _exportable(rb: RuleBase, fmt: str) -> list[str]:
    if fmt == "fis":
        return fis.refusals(rb)
    if fmt in ("fcl", "fcl-iec"):
        return fcl.refusals(rb, "iec" if fmt == "fcl-iec" else "named")
    return fll.refusals(rb)


FORMATS = ["fis", "fcl", "fcl-iec", "fll"]


@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize("name", TYPE1_SHIPPED)
def test_shipped_rule_bases_round_trip_yaml_to_format_to_yaml(name: str, fmt: str) -> None:
    rb = load(name)
    refused = _exportable(rb, fmt)
    if refused:
        with pytest.raises(ExportError) as err:
            _write(rb, fmt)
        assert all(item in str(err.value) for item in refused)
        return
    back = _read(_write(rb, fmt), fmt)
    want = as_format_holds(rb, fmt)
    assert back == want
    assert dump(back) == dump(want)  # and so YAML -> X -> YAML gives the same YAML
    assert loads_rulebase(dump(back)) == back


@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize("seed", range(40))
def test_random_rule_bases_round_trip_exactly(seed: int, fmt: str) -> None:
    rb = random_rulebase(seed, matlab_shapes=True)
    if fmt == "fcl-iec":  # point lists hold only piecewise-linear terms
        rb = replace(
            rb,
            inputs=tuple(map(_piecewise_linear, rb.inputs)),
            outputs=tuple(map(_piecewise_linear, rb.outputs)),
        )
    refused = _exportable(rb, fmt)
    if refused:  # only FIS refuses these: an input twice in a rule, a bounded sum
        assert fmt == "fis"
        assert all("appears twice" in item or "'bounded_sum'" in item for item in refused)
        return
    assert _read(_write(rb, fmt), fmt) == as_format_holds(rb, fmt)


def test_the_random_round_trips_hold_every_matlab_shape_on_inputs_and_outputs() -> None:
    rbs = [random_rulebase(seed, matlab_shapes=True) for seed in range(40)]
    for group in ("inputs", "outputs"):
        held = {t.shape for rb in rbs for v in getattr(rb, group) for t in v.terms}
        assert set(MATLAB_SHAPES) <= held, (group, set(MATLAB_SHAPES) - held)


def _piecewise_linear(var: Variable) -> Variable:
    """``var`` with each smooth term replaced by a triangle around its centre."""
    width = (var.high - var.low) / 4
    terms = []
    for t in var.terms:
        if not t.is_piecewise_linear:
            c = membership.centre(t, var.low, var.high)
            t = Term(t.name, "triangle", (c - width, c, c + width))
        terms.append(t)
    return replace(var, terms=tuple(terms))


def test_clamped_rule_base_is_refused_by_fis_and_fcl_unless_loss_is_allowed() -> None:
    rb = load("macvicar_whelan")
    for fmt in ("fis", "fcl"):
        with pytest.raises(ExportError, match="out_of_range: clamp"):
            dumps(rb, fmt)
    assert "lock-range: true" in dumps(rb, "fll")
    assert fll.loads(dumps(rb, "fll")).out_of_range == "clamp"


@pytest.mark.parametrize(
    "change, fmt, match",
    [
        ({"defuzzifier": "weighted_average"}, "fis", "Mamdani weighted_average|wtaver"),
        ({"defuzzifier": "weighted_average"}, "fll", "Tsukamoto"),
        ({"defuzzifier": "weighted_average"}, "fcl", "COGS"),
        ({"aggregation": "bounded_sum"}, "fis", "aggregation 'bounded_sum'"),
    ],
)
def test_what_a_format_cannot_express_is_refused_naming_it(
    change: dict[str, str], fmt: str, match: str
) -> None:
    rb = replace(load("gaussian5"), out_of_range="extend")
    if "aggregation" in change:
        rb = replace(rb, operators=replace(rb.operators, aggregation=change["aggregation"]))
    else:
        rb = replace(rb, **change)  # type: ignore[arg-type]
    with pytest.raises(ExportError, match=match):
        dumps(rb, fmt, allow_loss=True)


def test_fis_refuses_nested_conditions_naming_the_rule() -> None:
    rb = replace(load("three_input"), out_of_range="extend")
    with pytest.raises(ExportError, match=r"rule 4: nested and/or"):
        dumps(rb, "fis", allow_loss=True)
