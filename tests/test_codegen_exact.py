"""The exact method: generated inference (C float/double, Python) against the exact engine.

The stated bound is rounding only (``fuzzkit.codegen.exact.ROUNDING_BOUND``: 256 machine
epsilons of the number type times the output's full scale); it is checked on 1e5 random points
plus every combination of edge values (range ends, beyond, +-1e30, +-inf, NaN) for the shipped
rule bases, on a random family (shapes x operators x defuzzifiers) in C and Python, with gcc and
clang, and under ASan/UBSan. Golden files: tests/golden/<rule base>/<target>-exact-<type>/.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import subprocess
from pathlib import Path

import numpy as np
import pytest
from _c_harness import HARNESS
from _codegen_util import CC, CLANG, needs_cc, require_sanitizers, rulebase, skip_no_cc
from _golden import GOLDEN, ULPS, check_golden, full_scale, golden_difference
from _random_rulebases import edged_rulebase, random_rulebase
from _sugeno_reference import sugeno_pi_by_hand

from fuzzkit.codegen.emit import emit
from fuzzkit.codegen.exact import ROUNDING_BOUND, emit_exact, not_yet, unsupported_reason
from fuzzkit.codegen.method import compile_rulebase
from fuzzkit.codegen.table_search import make_table
from fuzzkit.codegen.toolchain import SANITIZE_FLAGS, STRICT_FLAGS, CompiledTable, run_compiler
from fuzzkit.codegen.verify import (
    _exact,
    compare,
    compare_exact,
    load_module,
    python_outputs,
    verification_points,
    verify_exact_c,
    verify_exact_python,
)
from fuzzkit.errors import CodegenError
from fuzzkit.formats.registry import load
from fuzzkit.fuzzy.model import Operators, RuleBase, Term, Variable
from fuzzkit.fuzzy.validation import check

SHIPPED = [
    "macvicar_whelan",
    "paper_table1",
    "gaussian5",
    "three_input",
    "temperature_pd",
    "sugeno_pi",
]
DEFUZZIFIERS = (
    "centroid",
    "bisector",
    "weighted_average",
    "mean_of_maximum",
    "smallest_of_maximum",
    "largest_of_maximum",
)
CONTINUOUS = ("centroid", "bisector", "weighted_average")


def random_family(seed: int, count: int) -> list[RuleBase]:
    """Random valid rule bases cycling through every defuzzifier and three output scales."""
    rng = np.random.default_rng(seed)
    family: list[RuleBase] = []
    i = 0
    while len(family) < count:
        lo, hi = [(-1.0, 1.0), (0.0, 30.0), (-1000.0, 1000.0)][i % 3]
        rb = edged_rulebase(rng, lo, hi)
        rb = dataclasses.replace(rb, defuzzifier=DEFUZZIFIERS[i % 6], name=f"rnd{seed}_{i}")
        i += 1
        if not check(rb):
            family.append(rb)
    return family


# --------------------------------------------------------------------------- C


@needs_cc
@skip_no_cc
@pytest.mark.parametrize("number_type", ["double", "float"])
@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_rule_bases_in_c_match_the_engine_to_rounding(name: str, number_type: str) -> None:
    rb = rulebase(name)
    result = verify_exact_c(rb, number_type, emit_exact(rb, "c", number_type))
    assert result.n_points >= 100_000
    assert result.ok, result.describe()
    assert result.tie_jumps == 0


@pytest.mark.slow
@needs_cc
@skip_no_cc
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_random_family_in_c_matches_the_engine_to_rounding(seed: int) -> None:
    for rb in random_family(seed, 12):
        for number_type in ("double", "float"):
            if not_yet(rb, rb.outputs[0], number_type) is not None:  # refused, by its class
                assert number_type == "float", rb
                assert "maxima of a probabilistic sum in float" in str(
                    unsupported_reason(rb, "float")
                )
                continue
            result = verify_exact_c(rb, number_type, emit_exact(rb, "c", number_type), n=3000)
            assert result.nan_mismatches == 0, (rb, result.describe())
            assert all(e <= a for e, a in zip(result.max_error, result.allowance, strict=True)), (
                rb,
                result.describe(),
            )
            if rb.defuzzifier in CONTINUOUS or number_type == "double":
                # double: ties are the engine's own 1e-12, so only a coincidence can jump
                assert result.tie_jumps <= 1, (rb, result.describe())
            else:
                # float levels carry 1e-7 rounding: nearly tied or flat maxima may jump
                assert result.ok, (rb, result.describe())


def _sanitized_run(tmp_path: Path, cc: list[str], rb: RuleBase, number_type: str, n: int) -> None:
    files = emit_exact(rb, "c", number_type)
    for rel, text in files.items():
        (tmp_path / rel).write_text(text)
    (tmp_path / "main.c").write_text(
        HARNESS.format(
            name=rb.name,
            t=number_type,
            ni=len(rb.inputs),
            no=len(rb.outputs),
            fmt="%lf",
            big="1e30",
        )
    )
    defines = ["-DWITH_FPI", "-DWITH_NAN"] if len(rb.inputs) == 2 else []
    require_sanitizers(cc)
    run_compiler(
        [*cc, *STRICT_FLAGS, *SANITIZE_FLAGS, *defines, "-o", "h", "main.c", f"{rb.name}.c", "-lm"],
        tmp_path,
    )
    points = verification_points(rb, n, seed=3)
    dtype = np.float32 if number_type == "float" else np.float64
    with np.errstate(over="ignore"):
        args = points.astype(dtype).astype(np.float64)
    text = "\n".join(" ".join(repr(float(v)) for v in row) for row in args)
    proc = subprocess.run(
        [str(tmp_path / "h")], input=text, capture_output=True, text=True, timeout=300, check=False
    )
    assert proc.returncode == 0, proc.stderr
    assert "runtime error" not in proc.stderr and "AddressSanitizer" not in proc.stderr
    lines = proc.stdout.splitlines()
    us = [float(line.split()[1]) for line in lines if line.startswith("u ")]
    if len(rb.inputs) == 2:
        assert len(us) == 400 and all(math.isfinite(u) for u in us)
    got = np.array(
        [[float(v) for v in line.split()] for line in lines if not line.startswith("u ")]
    )
    result = compare_exact(rb, number_type, "c sanitized", got, _exact(rb, args))
    assert result.ok, result.describe()


def _compiler(name: str) -> list[str]:
    if name == "clang":
        if CLANG is None:
            pytest.skip("clang not installed (apt-get install -y clang); gcc covers it here")
        return [CLANG]
    assert CC is not None
    return CC


#: Sanitized runs: (rule base, number type, random points). The Sugeno stage in double over
#: extended inputs, the float code's own exp, log, pow and erfc, besides MacVicar-Whelan.
SANITIZED = {
    "macvicar_whelan-double": (lambda: rulebase("macvicar_whelan"), "double", 100_000),
    "macvicar_whelan-float": (lambda: rulebase("macvicar_whelan"), "float", 100_000),
    "sugeno_pi-extend-float": (
        lambda: dataclasses.replace(rulebase("sugeno_pi"), out_of_range="extend"),
        "float",
        1000,
    ),
    "gaussian3x3-float": (
        lambda: load(Path(__file__).parent / "data" / "gaussian3x3.yaml"),
        "float",
        1000,
    ),
    # Gaussian outputs under a probabilistic sum: the proven quadrature (smooth_quadrature)
    "gaussian3x3-psum-float": (
        lambda: dataclasses.replace(
            load(Path(__file__).parent / "data" / "gaussian3x3.yaml"),
            operators=Operators("product", "max", "product", "probabilistic_sum"),
        ),
        "float",
        1000,
    ),
    # every smooth input shape, and the float code's own pow (a bell's)
    "smooth_inputs-float": (
        lambda: load(Path(__file__).parent / "data" / "fis" / "smooth_inputs.fis"),
        "float",
        1000,
    ),
    # interval type-2 (codegen.exact_type2): its own unit, with the fuzzy-PI step
    "macvicar_whelan_it2-double": (lambda: rulebase("macvicar_whelan_it2"), "double", 2000),
    "macvicar_whelan_it2-float": (lambda: rulebase("macvicar_whelan_it2"), "float", 2000),
}


@needs_cc
@skip_no_cc
@pytest.mark.parametrize("compiler", ["cc", "clang"])
@pytest.mark.parametrize("case", sorted(SANITIZED))
def test_exact_c_runs_clean_under_sanitizers(tmp_path: Path, compiler: str, case: str) -> None:
    make, number_type, n = SANITIZED[case]
    _sanitized_run(tmp_path, _compiler(compiler), make(), number_type, n)


@pytest.mark.slow
@needs_cc
@skip_no_cc
@pytest.mark.parametrize("compiler", ["cc", "clang"])
def test_every_operator_path_runs_clean_under_sanitizers(tmp_path: Path, compiler: str) -> None:
    cc = _compiler(compiler)
    gaussian = load(Path(__file__).parent / "data" / "gaussian3x3.yaml")  # erfc closed form
    cases = [rulebase("three_input"), rulebase("gaussian5"), gaussian, *random_family(7, 12)]
    seen = set()
    for k, rb in enumerate(cases):
        smooth = rb.outputs[0].terms[0].shape == "gaussian"
        key = (rb.operators.implication, rb.operators.aggregation, rb.defuzzifier, smooth)
        if key in seen:
            continue
        seen.add(key)
        folder = tmp_path / str(k)
        folder.mkdir()
        _sanitized_run(folder, cc, rb, "double", 1000)
    assert len(seen) >= 8


@needs_cc
@skip_no_cc
@pytest.mark.parametrize("compiler", ["cc", "clang"])
@pytest.mark.parametrize("name", SHIPPED)
def test_exact_c_compiles_without_a_diagnostic(tmp_path: Path, compiler: str, name: str) -> None:
    cc = _compiler(compiler)
    for number_type in ("double", "float"):
        files = emit_exact(rulebase(name), "c", number_type)
        for rel, text in files.items():
            (tmp_path / rel).write_text(text)
        proc = run_compiler([*cc, *STRICT_FLAGS, "-O2", "-c", f"{name}.c"], tmp_path)
        assert proc.stderr.strip() == ""


@needs_cc
@skip_no_cc
def test_exact_fuzzy_pi_matches_the_loop_on_the_engine() -> None:
    rb = rulebase("macvicar_whelan")
    kp, ki, kx, u_min, u_max = 0.8, 0.5, 0.05, -0.3, 0.3
    rng = np.random.default_rng(5)
    meas = np.cumsum(rng.normal(0.0, 0.2, 300))
    meas[[40, 41, 120]] = [math.nan, math.inf, math.nan]
    sp = np.ones_like(meas)
    with CompiledTable(emit_exact(rb, "c", "double"), rb.name, "double", 2, 1, fpi=True) as lib:
        u_c, faults = lib.fpi_run([kp, ki, kx, u_min, u_max], sp, meas)
    py = load_module(emit_exact(rb, "python"), rb.name).FuzzyPI(kp, ki, kx, u_min, u_max)
    from fuzzkit.fuzzy.inference import Engine

    f = Engine(rb).point_function()
    u, e_prev, started, want = 0.0, 0.0, False, []
    for s, m in zip(sp, meas, strict=True):
        e = s - m
        if math.isfinite(e):
            de = e - e_prev if started else 0.0
            u = min(max(u + kx * f(ki * e, kp * de), u_min), u_max)
            e_prev, started = e, True
        want.append(u)
        assert py.step(s, m) == pytest.approx(u, abs=1e-12)
    np.testing.assert_allclose(u_c, want, atol=1e-12)
    assert int(faults[-1]) == 3 and py.faults == 3


# --------------------------------------------------------------------------- Python


@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_rule_bases_in_python_match_the_engine_to_rounding(name: str) -> None:
    rb = rulebase(name)
    result = verify_exact_python(rb, emit_exact(rb, "python"), n=4000)
    assert result.ok, result.describe()
    assert result.tie_jumps == 0


def test_random_family_in_python_matches_the_engine_to_rounding() -> None:
    for rb in random_family(11, 18):
        result = verify_exact_python(rb, emit_exact(rb, "python"), n=300)
        assert result.nan_mismatches == 0, (rb, result.describe())
        assert result.tie_jumps <= 1 and all(
            e <= a for e, a in zip(result.max_error, result.allowance, strict=True)
        ), (rb, result.describe())


def test_python_uses_only_the_standard_library() -> None:
    text = emit_exact(rulebase("three_input"), "python")["three_input.py"]
    imports = {line.split()[1] for line in text.splitlines() if line.startswith(("import", "from"))}
    assert imports <= {"__future__", "math", "collections.abc"}


# --------------------------------------------------------------------------- both methods


@needs_cc
@skip_no_cc
def test_random_family_through_the_table_method_stays_within_its_bound() -> None:
    tested = 0
    for rb in random_family(3, 30):
        if rb.defuzzifier not in CONTINUOUS:
            continue
        try:
            table = make_table(rb, number_type="double", resolution=9)
        except CodegenError as exc:  # no rule fires somewhere: a table refuses, as documented
            assert "undefined" in str(exc)
            continue
        tested += 1

        files = emit(rb, table, "c")
        points = verification_points(rb, 2000)
        with CompiledTable(
            files, rb.name, "double", len(rb.inputs), 1, fpi=len(rb.inputs) == 2
        ) as lib:
            got = lib.eval_batch(points)
        result = compare(rb, table, "c", got, _exact(rb, points))
        assert result.ok, (rb, result.describe())
        module = load_module(emit(rb, table, "python"), rb.name)
        result = compare(rb, table, "py", python_outputs(module.eval, points), _exact(rb, points))
        assert result.ok, (rb, result.describe())
    assert tested >= 3


@needs_cc
@skip_no_cc
@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_rule_bases_through_the_table_method_stay_within_the_bound(name: str) -> None:
    rb = rulebase(name)
    table = make_table(rb, number_type="double", resolution=9)
    points = verification_points(rb, 5000)
    exact = _exact(rb, points)
    with CompiledTable(
        emit(rb, table, "c"), rb.name, "double", len(rb.inputs), len(rb.outputs),
        fpi=len(rb.inputs) == 2,
    ) as lib:  # fmt: skip
        result = compare(rb, table, "c", lib.eval_batch(points), exact)
    assert result.ok, result.describe()
    module = load_module(emit(rb, table, "python"), rb.name)
    result = compare(rb, table, "py", python_outputs(module.eval, points[:2000]), exact[:2000])
    assert result.ok, result.describe()


# --------------------------------------------------------------------------- choosing a method


def test_auto_takes_the_exact_method_for_a_discontinuous_defuzzifier() -> None:
    rb = dataclasses.replace(rulebase("macvicar_whelan"), defuzzifier="mean_of_maximum")
    result = compile_rulebase(rb, "python", "double")
    assert result.method == "exact" and "discontinuous" in result.reason


def test_table_method_refuses_a_discontinuous_defuzzifier_without_a_resolution() -> None:
    rb = dataclasses.replace(rulebase("macvicar_whelan"), defuzzifier="largest_of_maximum")
    with pytest.raises(CodegenError, match=r"discontinuous.*--method exact"):
        compile_rulebase(rb, "c", "float", method="table")
    result = compile_rulebase(rb, "c", "float", method="table", resolution=9)
    assert result.method == "table"
    assert result.warnings and "discontinuous" in result.warnings[0]
    assert "% of the output range" in result.warnings[0]


def test_auto_takes_a_table_when_it_fits_the_budget_and_says_so() -> None:
    rb = rulebase("macvicar_whelan")
    result = compile_rulebase(rb, "c", "float", tolerance=0.05, max_bytes=8192)
    assert result.method == "table" and result.table is not None
    assert result.table.memory_bytes <= 8192
    assert "meets the tolerance of 5 % of the output range" in result.reason


def test_auto_takes_the_exact_method_when_no_table_fits_the_budget() -> None:
    rb = rulebase("macvicar_whelan")
    result = compile_rulebase(rb, "c", "float", tolerance=1e-3, max_bytes=4096)
    assert result.method == "exact" and "--max-bytes 4096" in result.reason


@pytest.mark.parametrize(
    "change, match",
    [
        (
            {
                "outputs": (Variable("du", -1, 1, (Term("g", "gaussian", (0.0, 0.3)),)),),
                "operators": Operators("min", "max", "min", "bounded_sum"),
            },
            r"term 'g' is a gaussian \(bounded_sum aggregation\): .* Gaussian output terms in "
            r"closed form under max aggregation, and by a proven quadrature under a "
            r"probabilistic sum with product implication",
        ),
        (
            {"outputs": (Variable("du", -1, 1, (Term("b", "bell", (0.3, 2.0, 0.0)),)),)},
            r"term 'b' is a bell \(max aggregation\): .* need a quadrature with a proven",
        ),
    ],
)
def test_exact_method_refuses_smooth_output_terms_with_the_reason(
    change: dict[str, object], match: str
) -> None:
    base = rulebase("macvicar_whelan")
    rb = dataclasses.replace(base, rules=(), **change)  # type: ignore[arg-type]
    assert unsupported_reason(rb) is not None
    with pytest.raises(CodegenError, match=match):
        emit_exact(rb, "c", "double")


def test_sugeno_pi_exact_code_equals_the_gain_scheduled_law_by_hand() -> None:
    rb = rulebase("sugeno_pi")
    module = load_module(emit_exact(rb, "python"), rb.name)
    rng = np.random.default_rng(2)
    points = rng.uniform(-1.3, 1.3, (500, 2))
    want = np.array([sugeno_pi_by_hand(e, de) for e, de in points])
    np.testing.assert_allclose(python_outputs(module.eval, points)[:, 0], want, atol=1e-14)
    if CC is not None:
        with CompiledTable(emit_exact(rb, "c", "double"), rb.name, "double", 2, 1, fpi=True) as lib:
            np.testing.assert_allclose(lib.eval_batch(points)[:, 0], want, atol=1e-14)


@pytest.mark.parametrize("seed", range(6))
def test_random_sugeno_rule_bases_in_python_match_the_engine(seed: int) -> None:
    rb = random_rulebase(seed, "clamp" if seed % 2 else "extend", sugeno=True)
    result = verify_exact_python(rb, emit_exact(rb, "python"), n=300)
    assert result.ok, (rb, result.describe())


@needs_cc
@skip_no_cc
def test_random_sugeno_rule_bases_in_c_match_the_engine() -> None:
    for seed in range(6):
        rb = random_rulebase(seed, "clamp" if seed % 2 else "extend", sugeno=True)
        for number_type in ("double", "float"):
            assert unsupported_reason(rb, number_type) is None
            result = verify_exact_c(rb, number_type, emit_exact(rb, "c", number_type), n=500)
            assert result.ok, (rb, number_type, result.describe())


@needs_cc
@skip_no_cc
def test_float_c_holds_linear_sugeno_terms_over_inputs_that_are_not_clamped() -> None:
    # extend: the local laws see the input itself (up to 1e100), far beyond float's range
    rb = dataclasses.replace(rulebase("sugeno_pi"), out_of_range="extend")
    rng = np.random.default_rng(5)
    far = [0.0, 0.3, -0.7, 1.0, -1.0, 5.0, -40.0, 1e30, -1e30, 3.0e38, -3.0e38, math.inf, -math.inf]
    points = np.vstack([rng.uniform(-3, 3, (200, 2)), np.array(list(itertools.product(far, far)))])
    args = points.astype(np.float32)
    want = np.array([sugeno_pi_by_hand(e, de, 1e100) for e, de in args.astype(np.float64)])
    with np.errstate(over="ignore"):
        want32 = want.astype(np.float32)
    assert np.isinf(want32).sum() > 10 and np.isfinite(want32).sum() > 200  # both kinds met
    files = emit_exact(rb, "c", "float")
    assert "computed in double" in files[f"{rb.name}.h"]
    with CompiledTable(files, rb.name, "float", 2, 1, fpi=True) as lib:
        got = lib.eval_batch(args)[:, 0]
    fin = np.isfinite(want32)
    np.testing.assert_array_equal(got[~fin], want32[~fin])
    # double sum rounded once: the float weights' rounding, relative to the value
    scale = np.maximum(1.0, np.abs(want[fin]))
    assert np.max(np.abs(got[fin] - want[fin]) / scale) < 16 * 2.0**-23


def test_exact_method_refuses_q15() -> None:
    with pytest.raises(CodegenError, match=r"floating point.*--method table"):
        emit_exact(rulebase("macvicar_whelan"), "c", "q15")


def test_stated_bound_is_rounding_sized() -> None:
    assert ROUNDING_BOUND["double"] < 1e-12 and ROUNDING_BOUND["float"] < 1e-4


# --------------------------------------------------------------------------- golden files

GOLDEN_CASES = [
    ("macvicar_whelan", "c", "double"),
    ("macvicar_whelan", "c", "float"),
    ("macvicar_whelan", "python", "double"),
    ("three_input", "c", "double"),
    ("three_input", "python", "double"),
]


@pytest.mark.parametrize("name, target, number_type", GOLDEN_CASES)
def test_exact_output_matches_golden_files(name: str, target: str, number_type: str) -> None:
    files = emit_exact(rulebase(name), target, number_type)
    folder = GOLDEN / name / f"{target}-exact-{number_type}"
    check_golden(folder, files, number_type, full_scale(rulebase(name)))


def test_a_changed_number_in_an_exact_golden_is_caught() -> None:
    # the exact-method files hold placeholders of 1e30: a tolerance scaled by the file's
    # largest literal would let any number change; the output's full scale (1) does not
    golden = (GOLDEN / "macvicar_whelan" / "c-exact-double" / "macvicar_whelan.c").read_text()
    assert "1e+30" in golden
    want = "0.0, 0.50000000000000022, 1e+30, 0.0, 0.49999999999999994, 1e+30,"
    assert want in golden
    scale = full_scale(rulebase("macvicar_whelan"))
    assert golden_difference(golden, golden, ULPS["double"], "double", scale) is None
    for changed in ("0.50000000000005", "0.5000001", "0.6"):
        got = golden.replace(want, want.replace("0.50000000000000022", changed))
        problem = golden_difference(got, golden, ULPS["double"], "double", scale)
        assert problem is not None and changed in problem
    # rounding-sized differences (what numpy/scipy releases change) still pass
    got = golden.replace(want, want.replace("0.50000000000000022", "0.50000000000000033"))
    assert golden_difference(got, golden, ULPS["double"], "double", scale) is None


# --------------------------------------------------------------------------- table search


def test_oversized_resolution_is_refused_before_any_work() -> None:
    with pytest.raises(CodegenError, match=r"255x255x255 table needs .* check points"):
        make_table(rulebase("three_input"), number_type="float", resolution=255)


@needs_cc
@skip_no_cc
def test_bound_certified_with_the_compiled_reference_equals_the_engines() -> None:
    """Check grids above 65536 points are evaluated by the compiled exact method."""
    from fuzzkit.codegen.table_search import _chunked, _engine_evaluator

    rb = dataclasses.replace(rulebase("macvicar_whelan"), defuzzifier="bisector")
    fast = make_table(rb, number_type="double", resolution=41)  # 321 x 321 check grid
    slow = make_table(
        rb, number_type="double", resolution=41, evaluate=_chunked(rb, _engine_evaluator(rb))
    )
    assert fast.check_points > 65_536
    np.testing.assert_array_equal(fast.values[0], slow.values[0])
    assert fast.bound == pytest.approx(slow.bound, rel=1e-9)
