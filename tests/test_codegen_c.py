"""Generated C: strict compilation, sanitizers, and equivalence with the exact engine."""

from __future__ import annotations

import math
import subprocess
from pathlib import Path

import numpy as np
import pytest
from _c_harness import HARNESS
from _codegen_util import (
    CC,
    CLANG,
    OFFSET_YAML,
    needs_cc,
    require_sanitizers,
    rulebase,
    skip_no_cc,
    sources,
    table,
)

from fuzzkit.codegen.lookup_table import Q15_ONE
from fuzzkit.codegen.toolchain import SANITIZE_FLAGS, STRICT_FLAGS, CompiledTable, run_compiler
from fuzzkit.codegen.verify import (
    ROUNDING,
    c_outputs_real,
    c_points,
    compare,
    verification_points,
)
from fuzzkit.errors import ToolchainError
from fuzzkit.fuzzy.inference import Engine

pytestmark = [needs_cc, skip_no_cc]

CASES = [
    ("macvicar_whelan", "float"),
    ("macvicar_whelan", "double"),
    ("macvicar_whelan", "q15"),
    ("gaussian5", "float"),
    ("three_input", "float"),
    ("three_input", "q15"),
    ("macvicar_whelan_it2", "float"),
    ("macvicar_whelan_it2", "double"),
]


def _exact(name: str, real: np.ndarray) -> np.ndarray:
    rb = rulebase(name)
    res = Engine(rb).evaluate({v.name: real[:, i] for i, v in enumerate(rb.inputs)})
    return np.column_stack([res[v.name] for v in rb.outputs])


def _write(folder: Path, files: dict[str, str]) -> list[str]:
    for rel, text in files.items():
        (folder / rel).write_text(text)
    return [rel for rel in files if rel.endswith(".c")]


@pytest.mark.parametrize("compiler", ["cc", "clang"])
@pytest.mark.parametrize("name, number_type", CASES)
def test_compiles_cleanly_with_strict_flags(
    tmp_path: Path, compiler: str, name: str, number_type: str
) -> None:
    if compiler == "clang" and CLANG is None:
        pytest.skip("clang not installed; the gcc run covers the strict build here")
    cc = [CLANG] if compiler == "clang" else CC
    assert cc is not None
    srcs = _write(tmp_path, sources(name, "c", number_type))  # type: ignore[arg-type]
    proc = run_compiler([*cc, *STRICT_FLAGS, "-O2", "-c", *srcs], tmp_path)
    assert proc.stderr.strip() == ""  # not even a note


@pytest.mark.parametrize("name, number_type", CASES)
def test_matches_exact_engine_on_random_and_edge_points(name: str, number_type: str) -> None:
    rb = rulebase(name)
    tab = table(name, number_type)  # type: ignore[arg-type]
    files = sources(name, "c", number_type)  # type: ignore[arg-type]
    points = verification_points(rb, 100_000, seed=1)
    args, real = c_points(tab, points)
    fpi = len(rb.inputs) == 2
    with CompiledTable(
        files, rb.name, number_type, len(rb.inputs), len(rb.outputs), fpi=fpi
    ) as lib:
        got = c_outputs_real(tab, lib.eval_batch(args))
    exact = _exact(name, real)
    result = compare(rb, tab, "c", got, exact)
    assert result.nan_mismatches == 0
    for err, bound, allow in zip(result.max_error, tab.bound, result.allowance, strict=True):
        assert err <= bound + allow, result.describe()
        # The bound is not vacuous: the worst random point comes close to it.
        assert err >= 0.5 * bound, result.describe()
    if number_type != "q15":
        # NaN in any input -> every output NaN; +-inf behaves as the nearer range end.
        nan_rows = np.isnan(points).any(axis=1)
        assert np.isnan(got[nan_rows]).all()
        assert not np.isnan(got[~nan_rows]).any()
        lows = np.array([v.low for v in rb.inputs])
        highs = np.array([v.high for v in rb.inputs])
        with CompiledTable(
            files, rb.name, number_type, len(rb.inputs), len(rb.outputs), fpi=False
        ) as lib:
            at_inf = lib.eval_batch([np.full(len(lows), math.inf), np.full(len(lows), -math.inf)])
            at_ends = lib.eval_batch([highs, lows])
        np.testing.assert_array_equal(at_inf, at_ends)


@pytest.mark.parametrize("name", ["macvicar_whelan", "three_input"])
def test_q15_is_bit_exact_with_the_python_model(name: str) -> None:
    rb = rulebase(name)
    tab = table(name, "q15")
    rng = np.random.default_rng(2)
    codes = rng.integers(-32768, 32768, size=(50_000, len(rb.inputs)))
    codes[:8] = [[-32768] * len(rb.inputs), [32767] * len(rb.inputs)] * 4
    with CompiledTable(
        sources(name, "c", "q15"), rb.name, "q15", len(rb.inputs), len(rb.outputs), fpi=False
    ) as lib:
        got = lib.eval_batch(codes.astype(np.int16)).astype(np.int64)
    model = np.column_stack(tab.interpolate_q15([codes[:, i] for i in range(len(rb.inputs))]))
    np.testing.assert_array_equal(got, model)


def test_q15_scaling_is_documented_and_applied() -> None:
    # 0.5 of full scale in, the exact engine's value at 0.5 out (within the bound).
    rb = rulebase("macvicar_whelan")
    tab = table("macvicar_whelan", "q15")
    header = sources("macvicar_whelan", "c", "q15")["macvicar_whelan.h"]
    assert "MACVICAR_WHELAN_IN0_FULL_SCALE 1.0" in header
    with CompiledTable(
        sources("macvicar_whelan", "c", "q15"), rb.name, "q15", 2, 1, fpi=False
    ) as lib:
        out = lib.eval_batch(np.array([[Q15_ONE // 2, -(Q15_ONE // 4)]], dtype=np.int16))
    exact = Engine(rb).evaluate_point(e=0.5, de=-0.25)["du"]
    assert abs(out[0, 0] / Q15_ONE - exact) <= tab.bound[0]


@pytest.mark.parametrize(
    "name, number_type",
    [
        ("macvicar_whelan", "float"),
        ("macvicar_whelan", "double"),
        ("macvicar_whelan", "q15"),
        ("three_input", "double"),
        ("three_input", "q15"),
        ("macvicar_whelan_it2", "float"),
        ("macvicar_whelan_it2", "double"),
    ],
)
def test_runs_clean_under_address_and_undefined_sanitizers(
    tmp_path: Path, name: str, number_type: str
) -> None:
    rb = rulebase(name)
    tab = table(name, number_type)  # type: ignore[arg-type]
    files = sources(name, "c", number_type)  # type: ignore[arg-type]
    srcs = _write(tmp_path, files)
    ctype = {"float": "float", "double": "double", "q15": "int16_t"}[number_type]
    (tmp_path / "main.c").write_text(
        HARNESS.format(
            name=name,
            t=ctype,
            ni=len(rb.inputs),
            no=len(rb.outputs),
            fmt="%lf",
            big="32767" if number_type == "q15" else "1e30",
        )
    )
    assert CC is not None
    require_sanitizers(CC)
    defines = [] if len(rb.inputs) != 2 else ["-DWITH_FPI"]
    if defines and number_type != "q15":
        defines.append("-DWITH_NAN")
    run_compiler(
        [*CC, *STRICT_FLAGS, *SANITIZE_FLAGS, *defines, "-o", "h", "main.c", *srcs], tmp_path
    )
    points = verification_points(rb, 2000, seed=3)
    args, real = c_points(tab, points)
    text = "\n".join(" ".join(repr(float(v)) for v in row) for row in args.astype(np.float64))
    proc = subprocess.run(
        [str(tmp_path / "h")], input=text, capture_output=True, text=True, timeout=120, check=False
    )
    assert proc.returncode == 0, proc.stderr
    assert "runtime error" not in proc.stderr and "AddressSanitizer" not in proc.stderr
    lines = proc.stdout.splitlines()
    us = [float(line.split()[1]) for line in lines if line.startswith("u ")]
    got = np.array(
        [[float(v) for v in line.split()] for line in lines if not line.startswith("u ")]
    )
    if len(rb.inputs) == 2:
        assert len(us) == 400 and all(math.isfinite(u) for u in us)
    got = c_outputs_real(tab, got)
    result = compare(rb, tab, "c", got, _exact(name, real))
    assert result.ok, result.describe()


def test_a_broken_file_under_sanitizers_fails_rather_than_skips(tmp_path: Path) -> None:
    # every sanitized command line names -fsanitize: only the probe decides a skip
    assert CC is not None
    require_sanitizers(CC)
    (tmp_path / "main.c").write_text("int main(void) { return undefined_symbol_xyz; }\n")
    with pytest.raises(ToolchainError, match="undefined_symbol_xyz") as caught:
        run_compiler([*CC, *STRICT_FLAGS, *SANITIZE_FLAGS, "-o", "h", "main.c"], tmp_path)
    assert "-fsanitize=address,undefined" in str(caught.value)


def test_compile_failure_is_a_toolchain_error_with_the_compiler_output(tmp_path: Path) -> None:
    files = dict(sources("macvicar_whelan", "c", "float"))
    files["macvicar_whelan.c"] += "\nint broken(void) { return undefined_symbol_xyz; }\n"
    with pytest.raises(ToolchainError, match="undefined_symbol_xyz"):
        CompiledTable(files, "macvicar_whelan", "float", 2, 1, fpi=True)


def test_rounding_allowance_is_small_against_the_bound() -> None:
    # The stated float allowance must not be what makes the check pass.
    tab = table("macvicar_whelan", "float")
    assert ROUNDING["float"] < 1e-3 * tab.bound[0]


ONE_INPUT_YAML = """
name: gain_1d
description: One input, one output (a soft-saturating gain) to exercise the 1-D code path.
inputs:
  x:
    range: [-2, 3]
    terms: {partition: triangular, labels: [N, Z, P]}
outputs:
  y:
    range: [-1, 1]
    terms: {partition: triangular, labels: [N, Z, P]}
operators: {and: min, or: max, implication: min, aggregation: max}
defuzzifier: centroid
rules:
  - {if: {x: N}, then: {y: N}}
  - {if: {x: Z}, then: {y: Z}}
  - {if: {x: P}, then: {y: P}}
"""


@pytest.mark.parametrize("number_type", ["float", "double", "q15"])
def test_one_input_rule_base_compiles_and_matches(tmp_path: Path, number_type: str) -> None:
    from fuzzkit.codegen.emit import emit
    from fuzzkit.codegen.table_search import make_table
    from fuzzkit.formats.registry import loads

    rb = loads(ONE_INPUT_YAML)
    tab = make_table(rb, number_type=number_type, resolution=21)  # type: ignore[arg-type]
    files = emit(rb, tab, "c")
    srcs = _write(tmp_path, files)
    assert CC is not None
    run_compiler([*CC, *STRICT_FLAGS, "-c", *srcs], tmp_path)
    points = verification_points(rb, 20_000, seed=6)
    args, real = c_points(tab, points)
    with CompiledTable(files, rb.name, number_type, 1, 1, fpi=False) as lib:
        got = c_outputs_real(tab, lib.eval_batch(args))
    res = Engine(rb).evaluate({"x": real[:, 0]})
    result = compare(rb, tab, "c", got, np.column_stack([res["y"]]))
    assert result.ok, result.describe()
    assert "no fuzzy-PI API" in files["gain_1d.h"]
    if number_type == "double":
        from fuzzkit.codegen.verify import load_module, python_outputs

        module = load_module(emit(rb, tab, "python"), rb.name)
        np.testing.assert_allclose(python_outputs(module.eval, points), got, atol=1e-12)


def test_float_c_on_a_range_far_from_zero_stays_within_its_bound() -> None:
    # float32 cannot hold 1000.3: the C's breakpoints are rounded, and the bound must be
    # certified for those breakpoints and float32 arithmetic (was 0.0203 against 9.2e-06).
    from fuzzkit.codegen.emit import emit
    from fuzzkit.codegen.table_search import make_table
    from fuzzkit.codegen.verify import verify_c
    from fuzzkit.formats.registry import loads

    rb = loads(OFFSET_YAML)
    tab = make_table(rb, number_type="float")
    files = emit(rb, tab, "c")
    result = verify_c(rb, tab, files, n=20_000)
    assert result.ok, result.describe()
    # The float32 values around the knot, where the worst error of the C sits.
    knot = np.float32(1000.3)
    near = [knot]
    for direction in (-np.inf, np.inf):
        x = knot
        for _ in range(3):
            x = np.nextafter(x, np.float32(direction))
            near.append(x)
    xs = np.array(near, dtype=np.float32)
    with CompiledTable(files, rb.name, "float", 1, 1, fpi=False) as lib:
        got = lib.eval_batch(xs[:, None]).astype(np.float64)[:, 0]
    exact = np.asarray(Engine(rb).evaluate({"a": xs.astype(np.float64)})["y"], dtype=np.float64)
    assert np.max(np.abs(got - exact)) <= tab.bound[0]
    # The Python model of the float C is operation for operation: identical results.
    np.testing.assert_array_equal(tab.interpolate([xs.astype(np.float64)])[0], got)


@pytest.mark.parametrize("compiler", ["cc", "clang"])
def test_description_with_comment_and_trigraph_sequences_compiles_strictly(
    tmp_path: Path, compiler: str
) -> None:
    # "/*" (-Wcomment) and "??/" (-Wtrigraphs) broke the strict build; "*/" ended the banner.
    from fuzzkit.codegen.emit import emit
    from fuzzkit.codegen.table_search import make_table
    from fuzzkit.codegen.verify import load_module
    from fuzzkit.formats.registry import loads

    if compiler == "clang" and CLANG is None:
        pytest.skip("clang not installed; the gcc run covers the strict build here")
    cc = [CLANG] if compiler == "clang" else CC
    assert cc is not None
    description = "Uses a /* nested comment */ a /*/ and trigraphs ??/ ??= ???/ end ??/"
    text = "\n".join(
        f"description: '{description}'" if line.startswith("description:") else line
        for line in ONE_INPUT_YAML.splitlines()
    )
    rb = loads(text)
    assert rb.description == description
    tab = make_table(rb, number_type="double", resolution=9)
    files = emit(rb, tab, "c")
    srcs = _write(tmp_path, files)
    proc = run_compiler([*cc, *STRICT_FLAGS, "-Wcomment", "-Wtrigraphs", "-c", *srcs], tmp_path)
    assert proc.stderr.strip() == ""
    for body in files.values():
        for bad in ("??", "/* nested", "/*/"):
            assert bad not in body
    module = load_module(emit(rb, tab, "python"), rb.name)
    assert "nested comment" in (module.__doc__ or "")


@pytest.mark.parametrize("number_type", ["float", "double"])
def test_c_gives_the_exact_engine_value_on_the_knot_lattice(number_type: str) -> None:
    # Zero error and zero change must give exactly the engine's output (no drift of an
    # integrating loop at equilibrium): the fit keeps knot-lattice nodes, the C reads them.
    from fuzzkit.codegen.table_search import SNAP_TO_ZERO, knots

    rb = rulebase("macvicar_whelan")
    files = sources("macvicar_whelan", "c", number_type)  # type: ignore[arg-type]
    dtype = np.float32 if number_type == "float" else np.float64
    k0, k1 = (knots(v).astype(dtype) for v in rb.inputs)
    g0, g1 = (g.ravel() for g in np.meshgrid(k0, k1, indexing="ij"))
    with CompiledTable(files, rb.name, number_type, 2, 1, fpi=False) as lib:
        got = lib.eval_batch(np.column_stack([g0, g1]))[:, 0]
    exact = Engine(rb).evaluate({"e": g0.astype(np.float64), "de": g1.astype(np.float64)})["du"]
    # Engine rounding noise below SNAP_TO_ZERO of the range is stored as exactly 0 (documented).
    exact = np.where(np.abs(exact) <= SNAP_TO_ZERO * 2.0, 0.0, exact)
    exact = np.asarray(exact).astype(dtype)
    assert exact[(g0 == 0) & (g1 == 0)][0] == 0.0
    # At a range end the fraction is 1 and w00 + 1 * (vm - w00) may round by an ulp.
    np.testing.assert_allclose(got, exact, rtol=0, atol=2 * float(np.finfo(dtype).eps))
    interior = (np.abs(g0) < 1) & (np.abs(g1) < 1)
    np.testing.assert_array_equal(got[interior], exact[interior])
    assert got[(g0 == 0) & (g1 == 0)][0] == exact[(g0 == 0) & (g1 == 0)][0]
