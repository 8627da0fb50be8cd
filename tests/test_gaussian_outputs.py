"""Gaussian output terms under max aggregation: the engine's closed forms (erf) against a fine
trapezoid (2e6 steps) of the aggregated set written out here, every term from its textbook
formula, for every implication and defuzzifier, at random points and corners. (scipy's
adaptive quad was tried as the reference and is off by 1e-9 at the clip points' kinks.)"""

from __future__ import annotations

import dataclasses
import itertools
from pathlib import Path

import numpy as np
import pytest
from _codegen_util import CC, CLANG, needs_cc, skip_no_cc
from _mamdani_reference import firing
from _pairwise import pairwise

from fuzzkit.cli import main
from fuzzkit.codegen.exact import emit_exact
from fuzzkit.codegen.toolchain import STRICT_FLAGS, run_compiler
from fuzzkit.codegen.verify import verify_exact_c, verify_exact_python
from fuzzkit.formats.registry import load
from fuzzkit.fuzzy.gaussian_geometry import GaussianGeometry
from fuzzkit.fuzzy.inference import Engine
from fuzzkit.fuzzy.model import RuleBase

FILE = Path(__file__).parent / "data" / "gaussian3x3.yaml"
MAXIMA = ("mean_of_maximum", "smallest_of_maximum", "largest_of_maximum")


def _variant(implication: str, defuzzifier: str) -> RuleBase:
    rb = load(FILE)
    ops = dataclasses.replace(rb.operators, implication=implication)
    return dataclasses.replace(rb, operators=ops, defuzzifier=defuzzifier)


#: Reference grid points: steps of 5e-6 (make test) or 1e-6 (make verify); the trapezoid's
#: error, kinks included, is below 1e-11 either way.
GRIDS = {"cover": 400_001, "full": 2_000_001}


def _set(rb: RuleBase, point: dict[str, float], y: np.ndarray) -> np.ndarray:
    """The aggregated set at ``y``, one rule at a time, each term from its textbook formula."""
    out = rb.outputs[0]
    product = rb.operators.implication == "product"
    agg = np.zeros_like(y)
    for rule, level in zip(rb.rules, firing(rb, point), strict=True):
        m, s = out.term(rule.consequents[0].term).params
        g = np.exp(-((y - m) ** 2) / (2.0 * s * s))
        agg = np.maximum(agg, level * g if product else np.minimum(level, g))
    return agg


def _reference(rb: RuleBase, point: dict[str, float], grid: int) -> float:
    out = rb.outputs[0]
    y = np.linspace(out.low, out.high, grid)
    f = _set(rb, point, y)
    if rb.defuzzifier == "centroid":
        return float(np.trapezoid(f * y, y) / np.trapezoid(f, y))
    if rb.defuzzifier == "bisector":
        cum = np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(y))])
        return float(np.interp(0.5 * cum[-1], cum, y))
    at = y[f >= f.max() * (1 - 1e-10)]
    som, lom = float(at[0]), float(at[-1])
    return {"smallest_of_maximum": som, "largest_of_maximum": lom}.get(
        rb.defuzzifier, 0.5 * (som + lom)
    )


@pytest.mark.parametrize("depth", ["cover", pytest.param("full", marks=pytest.mark.verify)])
@pytest.mark.parametrize("implication", ["min", "product"])
@pytest.mark.parametrize("defuzzifier", ["centroid", "bisector", *MAXIMA])
def test_gaussian_outputs_in_closed_form_equal_a_fine_trapezoid(
    implication: str, defuzzifier: str, depth: str
) -> None:
    rb = _variant(implication, defuzzifier)
    engine = Engine(rb)
    assert isinstance(engine._outputs[0].geometry, GaussianGeometry)  # type: ignore[union-attr]
    rng = np.random.default_rng(7)
    points = [(-1.0, 1.0), (1.0, 1.0), *rng.uniform(-1, 1, (4, 2)).tolist()]
    if depth == "cover":
        points = points[1:3]
    grid = GRIDS[depth]
    # the maxima are off by up to one reference step
    tol = 2 * 2.0 / (grid - 1) if defuzzifier in MAXIMA else 1e-10
    for e, de in points:
        got = engine.evaluate_point(e=e, de=de)["du"]
        assert got == pytest.approx(_reference(rb, {"e": e, "de": de}, grid), abs=tol), (e, de)


def test_a_101x101_surface_of_gaussian_outputs_is_the_reference_where_sampled() -> None:
    rb = load(FILE)
    g = np.linspace(-1, 1, 101)
    e, de = np.meshgrid(g, g)
    surface = Engine(rb).evaluate({"e": e, "de": de})["du"]
    assert np.all(np.isfinite(surface))
    for i, j in [(50, 50), (13, 77)]:
        want = _reference(rb, {"e": float(e[i, j]), "de": float(de[i, j])}, GRIDS["cover"])
        assert surface[i, j] == pytest.approx(want, abs=1e-10)


# --------------------------------------------------------------------------- generated code


def _narrow(implication: str, defuzzifier: str = "centroid") -> RuleBase:
    """The same with input terms of sigma 0.05: between them every strength is 1e-20 or less."""
    rb = _variant(implication, defuzzifier)
    inputs = tuple(
        dataclasses.replace(
            v, terms=tuple(dataclasses.replace(t, params=(t.params[0], 0.05)) for t in v.terms)
        )
        for v in rb.inputs
    )
    return dataclasses.replace(rb, inputs=inputs)


DEFUZZIFIERS = ("centroid", "bisector", *MAXIMA)
#: implication x number type x defuzzifier: every pair in make test, the product in make verify
C_AXES = (("min", "product"), ("double", "float"), DEFUZZIFIERS)
C_CASES = [pytest.param(*row, id="cover-" + "-".join(row)) for row in pairwise(C_AXES)] + [
    pytest.param(*row, id="full-" + "-".join(row), marks=pytest.mark.verify)
    for row in itertools.product(*C_AXES)
]


@pytest.mark.parametrize("implication", ["min", "product"])
@pytest.mark.parametrize("defuzzifier", DEFUZZIFIERS)
def test_generated_python_of_gaussian_outputs_equals_the_engine(
    implication: str, defuzzifier: str
) -> None:
    for rb in (_variant(implication, defuzzifier), _narrow(implication, defuzzifier)):
        result = verify_exact_python(rb, emit_exact(rb, "python"), n=1000)
        assert result.ok, result.describe()


@needs_cc
@skip_no_cc
@pytest.mark.parametrize("implication, number_type, defuzzifier", C_CASES)
def test_generated_c_of_gaussian_outputs_equals_the_engine(
    implication: str, number_type: str, defuzzifier: str
) -> None:
    narrow = _narrow(implication, defuzzifier)
    if number_type == "float":
        # product AND of two 1e-22 memberships is 1e-44, below float's normal range (its
        # levels have lost their digits there): min AND keeps them at 1e-22
        narrow = dataclasses.replace(
            narrow, operators=dataclasses.replace(narrow.operators, and_="min")
        )
    for rb in (_variant(implication, defuzzifier), narrow):
        result = verify_exact_c(rb, number_type, emit_exact(rb, "c", number_type), n=5000)
        assert result.ok, result.describe()


def test_where_every_strength_is_tiny_the_engine_keeps_the_flat_tops() -> None:
    rb = _narrow("min")
    point = {"e": 0.5, "de": -0.45}
    assert 0.0 < max(firing(rb, point)) < 1e-15
    got = Engine(rb).evaluate_point(point)["du"]
    assert got == pytest.approx(_reference(rb, point, GRIDS["cover"]), abs=1e-10)


@needs_cc
@skip_no_cc
@pytest.mark.parametrize("compiler", ["cc", "clang"])
def test_generated_c_of_gaussian_outputs_compiles_without_a_diagnostic(
    tmp_path: Path, compiler: str
) -> None:
    cc = CC if compiler == "cc" else ([CLANG] if CLANG else None)
    if cc is None:
        pytest.skip("clang not installed (apt-get install -y clang); gcc covers it here")
    cases = [(imp, d, "double") for imp in ("min", "product") for d in DEFUZZIFIERS[:3]]
    for implication, defuzzifier, number_type in [*cases, ("product", "bisector", "float")]:
        rb = _variant(implication, defuzzifier)
        for rel, text in emit_exact(rb, "c", number_type).items():
            (tmp_path / rel).write_text(text)
        proc = run_compiler([*cc, *STRICT_FLAGS, "-O2", "-c", f"{rb.name}.c"], tmp_path)
        assert proc.stderr.strip() == ""


@needs_cc
@skip_no_cc
@pytest.mark.parametrize(
    "path, number_type",
    [
        (FILE, "double"),
        (FILE, "float"),
        (Path(__file__).parent / "data/fis/gauss_outputs.fis", "double"),
    ],
)
def test_gaussian_outputs_compile_and_verify_from_the_command_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], path: Path, number_type: str
) -> None:
    # gauss_outputs.fis: MATLAB gaussmf outputs (sigma 0.2), bisector, strengths of 1e-20
    args = ["compile", str(path), "--target", "c", "--type", number_type, "--method", "exact"]
    code = main([*args, "--verify", "--out", str(tmp_path / "out"), "--quiet"])
    text = capsys.readouterr().out
    assert code == 0, text
    assert ": ok on" in text and "exact inference" in text
