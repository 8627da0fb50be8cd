"""The shape registry: its records agree with the shapes' behaviour, and nothing falls back.

Every registered shape needs an example here (:data:`EXAMPLES`): the tests below then check its
support, centre, spellings and piecewise-linear form against its membership function, and that
the documentation lists it.
"""

from __future__ import annotations

import ast
import math
import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from fuzzkit.codegen import exact
from fuzzkit.formats import fcl, fis, fll
from fuzzkit.formats.yaml_writer import dump
from fuzzkit.fuzzy import membership, shapes
from fuzzkit.fuzzy.model import Consequent, Proposition, Rule, RuleBase, Term, Variable
from fuzzkit.fuzzy.shapes import REGISTRY, UnknownShapeError
from fuzzkit.fuzzy.validation import check, uncovered

ROOT = Path(__file__).resolve().parent.parent

#: A valid example of every registered shape (a new shape needs one).
EXAMPLES: dict[str, tuple[float, ...]] = {
    "triangle": (0.0, 1.0, 3.0),
    "trapezoid": (0.0, 1.0, 2.0, 4.0),
    "left_shoulder": (-1.0, 1.0),
    "right_shoulder": (-1.0, 1.0),
    "gaussian": (1.0, 2.0),
    "bell": (2.0, 1.5, 0.5),
    "sigmoid": (2.0, 1.0),
    "singleton": (0.5,),
    "gaussian_product": (2.0, 0.5, 5.0, 1.5),
    "s_shape": (1.0, 8.0),
    "z_shape": (1.0, 8.0),
    "pi_shape": (1.0, 4.0, 5.0, 9.0),
    "sigmoid_difference": (2.0, 3.0, 6.0, 5.0),
    "sigmoid_product": (2.0, 3.0, -5.0, 8.0),
    "constant": (1.5,),
    "linear": (0.5, 2.0),
}
MEMBERSHIP = [n for n, s in REGISTRY.items() if not s.sugeno]
LOW, HIGH = -3.0, 10.0
GRID = np.linspace(LOW, HIGH, 130_001)


def test_every_registered_shape_has_an_example_here() -> None:
    assert list(EXAMPLES) == list(REGISTRY)


@pytest.mark.parametrize("name", list(REGISTRY))
def test_the_example_is_valid_and_the_record_is_complete(name: str) -> None:
    s = REGISTRY[name]
    assert s.check(EXAMPLES[name]) == []
    assert (s.mu is None) == s.sugeno == (s.centre is None)
    assert s.piecewise_linear == (s.points is not None) == (s.trapezoid is not None)
    for spelling in (*s.fis, *s.fll, *s.fcl):
        for item in spelling.layout:
            assert item in s.params or item == "*" or math.isinf(float(item)), (name, item)


@pytest.mark.parametrize("name", MEMBERSHIP)
def test_support_is_exactly_where_the_membership_is_positive(name: str) -> None:
    s = REGISTRY[name]
    p = EXAMPLES[name]
    pieces = s.support(p)
    inside = np.zeros(GRID.shape, dtype=bool)
    for lo, lo_in, hi, hi_in in pieces:
        inside |= ((lo < GRID) | (lo_in & (lo == GRID))) & ((hi > GRID) | (hi_in & (hi == GRID)))
    mu = s.evaluate(GRID, p)
    assert np.all(mu[~inside] == 0.0)
    assert np.all(mu[inside] > 0.0) or s.impulse
    if s.impulse:  # a single point, not on the grid: evaluate it there
        assert float(s.evaluate(np.array([p[0]]), p)[0]) == 1.0


@pytest.mark.parametrize("name", MEMBERSHIP)
def test_nan_gives_nan_as_every_docstring_says(name: str) -> None:
    s = REGISTRY[name]
    assert s.mu is not None and "NaN gives NaN" in (s.mu.__doc__ or "")
    got = s.evaluate(np.array([math.nan, 0.5]), EXAMPLES[name])
    assert math.isnan(got[0]) and not math.isnan(got[1])


@pytest.mark.parametrize("name", [n for n in MEMBERSHIP if not REGISTRY[n].impulse])
def test_centre_is_the_middle_of_where_the_membership_is_largest(name: str) -> None:
    p = EXAMPLES[name]
    mu = REGISTRY[name].evaluate(GRID, p)
    top = GRID[mu >= mu.max() - 1e-9]
    want = 0.5 * (top[0] + top[-1])
    got = membership.centre(Term("t", name, p), LOW, HIGH)
    assert got == pytest.approx(want, abs=2e-3 * (HIGH - LOW))


def test_a_singletons_centre_is_its_value() -> None:
    assert membership.centre(Term("t", "singleton", (0.5,)), LOW, HIGH) == 0.5


@pytest.mark.parametrize("name", [n for n in MEMBERSHIP if REGISTRY[n].piecewise_linear])
def test_the_piecewise_linear_form_and_points_draw_the_membership(name: str) -> None:
    s = REGISTRY[name]
    p = EXAMPLES[name]
    assert s.points is not None
    xs, ys = zip(*s.points(p), strict=True)
    np.testing.assert_allclose(np.interp(GRID, xs, ys), s.evaluate(GRID, p), atol=1e-12)
    b, c, rise, fall = membership.trapezoid_form(Term("t", name, p))
    form = np.clip(np.minimum(1 + (GRID - b) * rise, 1 + (c - GRID) * fall), 0, 1)
    np.testing.assert_allclose(form, s.evaluate(GRID, p), atol=1e-12)


@pytest.mark.parametrize("fmt", ["fis", "fll", "fcl"])
@pytest.mark.parametrize("name", list(REGISTRY))
def test_what_a_format_writes_it_reads_back_as_the_same_shape(fmt: str, name: str) -> None:
    written = shapes.write_term(fmt, name, EXAMPLES[name])
    if written is None:
        assert not getattr(REGISTRY[name], fmt)
        return
    assert shapes.read_term(fmt, *written) == (name, EXAMPLES[name])


@pytest.mark.parametrize(
    ("fmt", "kind", "values", "want"),
    [
        ("fis", "trapmf", (-math.inf, -math.inf, 1.0, 2.0), ("left_shoulder", (1.0, 2.0))),
        ("fis", "trapmf", (1.0, 2.0, math.inf, math.inf), ("right_shoulder", (1.0, 2.0))),
        ("fis", "trapmf", (0.0, 1.0, 2.0, 3.0), ("trapezoid", (0.0, 1.0, 2.0, 3.0))),
        ("fis", "rampmf", (5.0, 3.0), ("left_shoulder", (3.0, 5.0))),
        ("fis", "rampmf", (3.0, 5.0), ("right_shoulder", (3.0, 5.0))),
        ("fll", "Ramp", (5.0, 3.0), ("left_shoulder", (3.0, 5.0))),
        ("fis", "gaussmf", (0.5, 2.0), ("gaussian", (2.0, 0.5))),
        ("fll", "Bell", (0.5, 2.0, 1.5), ("bell", (2.0, 1.5, 0.5))),
        (
            "fll",
            "SigmoidProduct",
            (3.0, 2.0, -5.0, 8.0),
            ("sigmoid_product", (2.0, 3.0, -5.0, 8.0)),
        ),
    ],
)
def test_a_name_means_the_shape_its_values_draw(
    fmt: str, kind: str, values: tuple[float, ...], want: tuple[str, tuple[float, ...]]
) -> None:
    assert shapes.read_term(fmt, kind, values) == want


# ---------------------------------------------------------------------------- unknown shapes

UNKNOWN = Term("odd", "cosine", (0.5, 1.0))


def _with_unknown(where: str) -> RuleBase:
    good_in = Variable("x", 0.0, 1.0, (Term("all", "trapezoid", (-1.0, 0.0, 1.0, 2.0)),))
    good_out = Variable("y", 0.0, 1.0, (Term("mid", "triangle", (0.0, 0.5, 1.0)),))
    inp = replace(good_in, terms=(*good_in.terms, UNKNOWN)) if where == "input" else good_in
    out = replace(good_out, terms=(*good_out.terms, UNKNOWN)) if where == "output" else good_out
    rule = Rule(Proposition("x", "all"), (Consequent("y", "mid"),))
    return RuleBase("odd", (inp,), (out,), (rule,), defuzzifier="weighted_average")


def test_an_unregistered_shape_raises_instead_of_falling_back() -> None:
    with pytest.raises(UnknownShapeError, match="unknown membership shape 'cosine'"):
        membership.centre(UNKNOWN, 0.0, 1.0)  # was: its first parameter, as for a singleton
    with pytest.raises(UnknownShapeError):
        uncovered(_with_unknown("input").inputs[0])  # was: positive everywhere
    with pytest.raises(UnknownShapeError):
        exact.unsupported_reason(_with_unknown("input"))
    with pytest.raises(UnknownShapeError):
        exact.unsupported_reason(_with_unknown("output"))
    with pytest.raises(UnknownShapeError):
        membership.evaluate_term(UNKNOWN, 0.5)
    with pytest.raises(UnknownShapeError):
        membership.trapezoid_form(UNKNOWN)
    for write in (dump, fis.dumps, fll.dumps, fcl.dumps):
        with pytest.raises(UnknownShapeError):
            write(_with_unknown("input"))


def test_validation_reports_an_unregistered_shape_as_a_problem() -> None:
    problems = check(_with_unknown("input"))
    assert any("unknown shape 'cosine'" in message for _, message in problems)


def test_the_exact_templates_have_no_fallback_for_a_kind_they_do_not_implement(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # a registered shape whose exact form names a kind no template implements: the generator
    # refuses it, and were the check skipped the templates fail instead of writing a singleton
    fake = replace(REGISTRY["gaussian"], exact=shapes.ExactForm("cosine", lambda p: p))
    monkeypatch.setitem(REGISTRY, "gaussian", fake)
    rb = _with_unknown("none")
    rb = replace(rb, inputs=(replace(rb.inputs[0], terms=(Term("g", "gaussian", (0.5, 1.0)),)),))
    rb = replace(rb, rules=(Rule(Proposition("x", "g"), (Consequent("y", "mid"),)),))
    with pytest.raises(exact.CodegenError, match="no exact template for kind 'cosine'"):
        exact.emit_exact(rb, "python")
    monkeypatch.setattr(exact, "TEMPLATE_KINDS", (*exact.TEMPLATE_KINDS, "cosine"))
    for target in ("python", "c"):
        with pytest.raises(exact.CodegenError, match="has no attribute 'kind_has_no_template"):
            exact.emit_exact(rb, target)


# ---------------------------------------------------------------------------- defined once


def _assignments(name: str) -> list[str]:
    found = []
    for folder in ("fuzzkit", "codegen"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            tree = ast.parse(path.read_text(encoding="utf-8"))
            for node in ast.walk(tree):
                targets = (
                    node.targets
                    if isinstance(node, ast.Assign)
                    else [node.target]
                    if isinstance(node, ast.AnnAssign)
                    else []
                )
                if any(isinstance(t, ast.Name) and t.id == name for t in targets):
                    found.append(str(path.relative_to(ROOT)))
    return found


@pytest.mark.parametrize(
    ("name", "home"),
    [
        ("SUGENO_SHAPES", "fuzzkit/fuzzy/shapes.py"),
        ("SHAPE_PARAMS", "fuzzkit/fuzzy/shapes.py"),
        ("PIECEWISE_LINEAR_SHAPES", "fuzzkit/fuzzy/shapes.py"),
        ("MAX_FILE_BYTES", "fuzzkit/located_yaml.py"),
    ],
)
def test_shared_constants_are_defined_once(name: str, home: str) -> None:
    assert _assignments(name) == [home]


def test_the_format_documentation_lists_every_registered_shape() -> None:
    text = (ROOT / "docs" / "rulebase-format.md").read_text(encoding="utf-8")
    text = text.split("### Terms", 1)[1].split("\n### ", 1)[0]
    table = re.findall(r"^\| `(\w+)` \|", text, flags=re.MULTILINE)
    assert table == list(REGISTRY)
