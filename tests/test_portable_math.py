"""The float C's own exp, log, pow and erfc (``codegen/backends/c/portable_math.c.jinja``).

libm's expf/logf/powf/erfcf differ by an ulp between C libraries, so float code computes them in
float arithmetic alone and gives the same bits on a microcontroller as on the host (``make
embedded`` compares them). Here they are compared with Python's ``math`` in double (an
independent, far more precise reference), in float ulps of the true value.
"""

from __future__ import annotations

import math
import shutil
import subprocess
from pathlib import Path

import numpy as np
import numpy.typing as npt
import pytest
from _codegen_util import CC, needs_cc, skip_no_cc

from fuzzkit.codegen.exact import emit_exact
from fuzzkit.codegen.toolchain import STRICT_FLAGS, run_compiler
from fuzzkit.formats.registry import load

GAUSSIAN = Path(__file__).parent / "data" / "gaussian3x3.yaml"
#: a rule base with a bell input term (and every other smooth input shape)
SMOOTH = Path(__file__).parent / "data" / "fis" / "smooth_inputs.fis"
#: e^(b ln a) turns ln a's rounding (2 ulps) into an error of the exponent of |b ln a| 2^-23:
#: measured 118 ulps for |b ln a| up to 80 (libm's powf: under 1; a bell's membership carries it)
POW_ULPS = 128.0
#: A float's smallest subnormal: results below float's normal range are held to a few of them.
TINY = 2.0**-149

MAIN = """#include <stdio.h>
#include "{name}.c"
int main(void)
{{
    char f[8];
    float x, r;
    while (scanf("%7s %a", f, &x) == 2) {{
        r = f[0] == 'l' ? {name}_logf(x) : (f[1] == 'x' ? {name}_expf(x) : {name}_erfcf(x));
        printf("%a\\n", (double)r);
    }}
    return 0;
}}
"""


def _build(folder: Path, source: Path, main: str) -> Path:
    """A program that includes ``source``'s float code and runs ``main`` on it."""
    if CC is None:
        pytest.skip("no C compiler")
    for rel, text in emit_exact(load(source), "c", "float").items():
        (folder / rel).write_text(text)
    (folder / "main.c").write_text(main.format(name=source.stem))
    run_compiler([*CC, *STRICT_FLAGS, "-O2", "-o", "pm", "main.c", "-lm"], folder)
    return folder / "pm"


@pytest.fixture(scope="module")
def program(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return _build(tmp_path_factory.mktemp("portable_math"), GAUSSIAN, MAIN)


def _run(program: Path, fn: str, xs: npt.NDArray[np.float32]) -> npt.NDArray[np.float64]:
    text = "\n".join(f"{fn} {float(x).hex()}" for x in xs)
    out = subprocess.run(
        [str(program)], input=text, capture_output=True, text=True, check=True, timeout=60
    ).stdout.split()
    return np.array([float.fromhex(v) if "n" not in v else float(v) for v in out])


def _ulps(got: npt.NDArray[np.float64], want: npt.NDArray[np.float64]) -> float:
    """Largest |got - want| in ulps of the float nearest ``want``."""
    ulp = np.spacing(np.abs(want.astype(np.float32))).astype(np.float64)
    return float(np.max(np.abs(got - want) / ulp))


def _check(program: Path, fn: str, xs: npt.NDArray[np.float32], ref: object, ulps: float) -> None:
    got = _run(program, fn, xs)
    want = np.array([ref(float(x)) for x in xs])  # type: ignore[operator]
    normal = np.abs(want) >= np.finfo(np.float32).tiny
    assert normal.sum() > 1000
    assert _ulps(got[normal], want[normal]) <= ulps
    assert np.all(np.abs(got[~normal] - want[~normal]) <= 3 * TINY)


@needs_cc
@skip_no_cc
def test_exp_is_within_1_5_ulps(program: Path) -> None:
    rng = np.random.default_rng(0)
    xs = np.concatenate(
        [rng.uniform(-104.0, 88.7, 6000), rng.uniform(-1, 1, 2000), rng.uniform(-1e-3, 1e-3, 500)]
    ).astype(np.float32)
    _check(program, "exp", xs, math.exp, 1.5)


@needs_cc
@skip_no_cc
def test_log_is_within_2_ulps(program: Path) -> None:
    rng = np.random.default_rng(1)
    xs = np.concatenate(
        [np.exp(rng.uniform(-103.0, 88.0, 6000)), rng.uniform(0.5, 2.0, 2000),
         rng.uniform(1e-45, 1e-38, 200)]  # subnormal arguments
    ).astype(np.float32)  # fmt: skip
    _check(program, "log", xs[xs > 0], math.log, 2.0)


@needs_cc
@skip_no_cc
def test_erfc_is_within_8_ulps_and_its_tail_keeps_its_relative_precision(program: Path) -> None:
    rng = np.random.default_rng(2)
    xs = np.concatenate([rng.uniform(-4.0, 10.2, 6000), rng.uniform(0.0, 1.0, 2000)])
    _check(program, "erfc", xs.astype(np.float32), math.erfc, 8.0)


@needs_cc
@skip_no_cc
@pytest.mark.parametrize(
    ("fn", "args", "want"),
    [
        ("exp", [math.nan, math.inf, -math.inf, 0.0, 89.0, -106.0],
         [math.nan, math.inf, 0, 1, math.inf, 0]),
        ("log", [math.nan, math.inf, -1.0, 0.0, 1.0],
         [math.nan, math.inf, math.nan, -math.inf, 0.0]),
        ("erfc", [math.nan, math.inf, -math.inf, 0.0, 11.0], [math.nan, 0.0, 2.0, 1.0, 0.0]),
    ],
)  # fmt: skip
def test_special_values(program: Path, fn: str, args: list[float], want: list[float]) -> None:
    got = _run(program, fn, np.array(args, dtype=np.float32))
    np.testing.assert_array_equal(got, np.array(want))


POW_MAIN = """#include <stdio.h>
#include "{name}.c"
int main(void)
{{
    float a, b;
    while (scanf("%a %a", &a, &b) == 2) {{
        printf("%a\\n", (double){name}_powf(a, b));
    }}
    return 0;
}}
"""


@pytest.fixture(scope="module")
def pow_program(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The float code of a rule base with a bell input term (whose |u|^(2 slope) is pow)."""
    return _build(tmp_path_factory.mktemp("portable_pow"), SMOOTH, POW_MAIN)


def _run_pow(
    program: Path, a: npt.NDArray[np.float32], b: npt.NDArray[np.float32]
) -> npt.NDArray[np.float64]:
    text = "\n".join(f"{float(x).hex()} {float(y).hex()}" for x, y in zip(a, b, strict=True))
    out = subprocess.run(
        [str(program)], input=text, capture_output=True, text=True, check=True, timeout=60
    ).stdout.split()
    return np.array([float.fromhex(v) if "n" not in v else float(v) for v in out])


@needs_cc
@skip_no_cc
def test_pow_is_within_its_stated_ulps_where_its_result_is_normal(pow_program: Path) -> None:
    """e^(b ln a) carries ln a's rounding times b ln a: within POW_ULPS of the true power
    while |b ln a| stays below 88 (the normal floats)."""
    rng = np.random.default_rng(3)
    b = rng.uniform(0.5, 12.0, 8000)
    log_a = rng.uniform(-80.0, 80.0, 8000) / b  # |b ln a| <= 80
    keep = np.abs(log_a) < 80.0  # a itself a normal float
    a, b = np.exp(log_a[keep]).astype(np.float32), b[keep].astype(np.float32)
    got = _run_pow(pow_program, a, b)
    want = np.array([math.pow(float(x), float(y)) for x, y in zip(a, b, strict=True)])
    assert _ulps(got, want) <= POW_ULPS


@needs_cc
@skip_no_cc
def test_pow_special_values(pow_program: Path) -> None:
    a = np.array([0.0, math.inf, math.nan, 1.0, 2.0], dtype=np.float32)
    b = np.array([2.0, 2.0, 2.0, 7.5, 0.5], dtype=np.float32)
    got = _run_pow(pow_program, a, b)
    np.testing.assert_array_equal(
        got, [0.0, math.inf, math.nan, 1.0, float(np.float32(math.sqrt(2.0)))]
    )


@needs_cc
@skip_no_cc
@pytest.mark.skipif(shutil.which("nm") is None, reason="nm (binutils) not installed")
@pytest.mark.parametrize("source", [GAUSSIAN, SMOOTH], ids=["gaussian3x3", "smooth_inputs"])
def test_float_code_calls_no_libm_exp_log_pow_or_erfc(tmp_path: Path, source: Path) -> None:
    assert CC is not None
    rb = load(source)
    for rel, text in emit_exact(rb, "c", "float").items():
        (tmp_path / rel).write_text(text)
    run_compiler([*CC, *STRICT_FLAGS, "-O2", "-c", f"{rb.name}.c"], tmp_path)
    nm = subprocess.run(["nm", "-u", f"{rb.name}.o"], cwd=tmp_path, capture_output=True, text=True)
    called = {line.split()[-1] for line in nm.stdout.splitlines() if line.strip()}
    assert called <= {"fabsf", "sqrtf", "memset"}, called  # no expf, logf, powf or erfcf
