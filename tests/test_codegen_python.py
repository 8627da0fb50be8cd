"""Generated Python and the fuzzy-PI step of both targets against independent references."""

from __future__ import annotations

import ast
import math

import numpy as np
import pytest
from _codegen_util import needs_cc, rulebase, skip_no_cc, sources, table

from fuzzkit.codegen.lookup_table import LookupTable, q15_fpi_codes
from fuzzkit.codegen.toolchain import CompiledTable
from fuzzkit.codegen.verify import compare, load_module, python_outputs, verification_points
from fuzzkit.fuzzy.inference import Engine


def _exact(name: str, points: np.ndarray) -> np.ndarray:
    rb = rulebase(name)
    res = Engine(rb).evaluate({v.name: points[:, i] for i, v in enumerate(rb.inputs)})
    return np.column_stack([res[v.name] for v in rb.outputs])


@pytest.mark.parametrize(
    "name", ["macvicar_whelan", "gaussian5", "three_input", "macvicar_whelan_it2"]
)
def test_generated_python_matches_exact_engine(name: str) -> None:
    rb = rulebase(name)
    tab = table(name, "double")
    module = load_module(sources(name, "python", "double"), name)
    points = verification_points(rb, 100_000, seed=4)
    got = python_outputs(module.eval, points)
    result = compare(rb, tab, "python", got, _exact(name, points))
    assert result.ok, result.describe()
    assert all(e >= 0.5 * b for e, b in zip(result.max_error, tab.bound, strict=True))
    assert module.eval([math.nan] * len(rb.inputs)) == tuple(
        [pytest.approx(math.nan, nan_ok=True)] * len(rb.outputs)
    )
    assert all(math.isnan(v) for v in module.eval([0.0] * (len(rb.inputs) - 1) + [math.nan]))


def test_generated_python_imports_only_the_standard_library() -> None:
    text = sources("macvicar_whelan", "python", "double")["macvicar_whelan.py"]
    imported = set()
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, ast.Import):
            imported |= {a.name.split(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module:
            imported.add(node.module.split(".")[0])
    assert imported <= {"__future__", "math", "bisect", "collections"}, imported


@needs_cc
@skip_no_cc
@pytest.mark.parametrize("name", ["macvicar_whelan", "three_input"])
def test_c_and_python_agree(name: str) -> None:
    rb = rulebase(name)
    module = load_module(sources(name, "python", "double"), name)
    points = verification_points(rb, 20_000, seed=5)
    py = python_outputs(module.eval, points)
    with CompiledTable(
        sources(name, "c", "double"), name, "double", len(rb.inputs), len(rb.outputs), fpi=False
    ) as lib:
        c = lib.eval_batch(points)
    np.testing.assert_allclose(c, py, rtol=0, atol=1e-12, equal_nan=True)


# ---------------------------------------------------------------------------------------------
# Fuzzy-PI: an independent reference loop (the paper's eqs. 5-9 written out here) over a
# first-order spring plant, with saturation and NaN/inf sensor samples.

GAINS = (0.8, 1.5, 0.05, -0.3, 0.6)  # kp, ki, kx, u_min, u_max


def reference_fpi(
    tab: LookupTable, gains: tuple[float, ...], setpoints: np.ndarray, measured: np.ndarray
) -> tuple[list[float], list[int]]:
    kp, ki, kx, u_min, u_max = gains
    u = min(max(0.0, u_min), u_max)
    e_prev = 0.0
    first = True
    faults = 0
    us, fs = [], []
    for sp, me in zip(setpoints, measured, strict=True):
        e = sp - me
        if math.isnan(e) or math.isinf(e):
            faults += 1
        else:
            de = 0.0 if first else e - e_prev
            out = tab.interpolate([ki * e, kp * de])[0]
            u = min(max(u + kx * float(out), u_min), u_max)
            e_prev = e
            first = False
        us.append(u)
        fs.append(faults)
    return us, fs


def spring_plant_measurements(tab: LookupTable, n: int = 400) -> tuple[np.ndarray, np.ndarray]:
    """Close the loop once with the reference controller to get a realistic measured trace."""
    rng = np.random.default_rng(7)
    setpoints = np.where(np.arange(n) < n // 2, 0.5, 2.0)  # the second half saturates at u_max
    kp, ki, kx, u_min, u_max = GAINS
    x = 0.0
    stiffness = 2.0
    measured = np.empty(n)
    u = 0.0
    e_prev = 0.0
    first = True
    for k in range(n):
        x += 0.2 * (u - x)  # first-order lag of the position towards the command
        measured[k] = stiffness * x + 0.002 * rng.standard_normal()
        if k in (50, 51, 120, 300):
            measured[k] = math.nan
        if k == 200:
            measured[k] = math.inf
        e = setpoints[k] - measured[k]
        if math.isfinite(e):
            de = 0.0 if first else e - e_prev
            u = min(max(u + kx * float(tab.interpolate([ki * e, kp * de])[0]), u_min), u_max)
            e_prev, first = e, False
    return setpoints, measured


def _check_trace(
    us: np.ndarray, faults: np.ndarray, ref_u: list[float], ref_f: list[int], atol: float
) -> None:
    np.testing.assert_allclose(us, ref_u, rtol=0, atol=atol)
    np.testing.assert_array_equal(faults, ref_f)
    assert ref_f[-1] == 5
    assert max(ref_u) == GAINS[4]  # saturation was reached, and held there by the clamp
    assert min(ref_u) >= GAINS[3]


def test_python_fpi_matches_reference_loop() -> None:
    tab = table("macvicar_whelan", "double")
    module = load_module(sources("macvicar_whelan", "python", "double"), "macvicar_whelan")
    sp, me = spring_plant_measurements(tab)
    ref_u, ref_f = reference_fpi(tab, GAINS, sp, me)
    ctl = module.FuzzyPI(*GAINS)
    us, fs = [], []
    for s, m in zip(sp, me, strict=True):
        us.append(ctl.step(float(s), float(m)))
        fs.append(ctl.faults)
    _check_trace(np.array(us), np.array(fs), ref_u, ref_f, atol=1e-12)
    ctl.reset()
    assert (ctl.u, ctl.faults) == (0.0, 0)
    assert ctl.step(0.5, 0.5) == pytest.approx(0.0, abs=1e-12)  # e = de = 0: no correction


@needs_cc
@skip_no_cc
@pytest.mark.parametrize("number_type, atol", [("double", 1e-12), ("float", 2e-4)])
def test_c_fpi_matches_reference_loop(number_type: str, atol: float) -> None:
    tab = table("macvicar_whelan", number_type)  # type: ignore[arg-type]
    sp, me = spring_plant_measurements(tab)
    ref_u, ref_f = reference_fpi(tab, GAINS, sp, me)
    with CompiledTable(
        sources("macvicar_whelan", "c", number_type),  # type: ignore[arg-type]
        "macvicar_whelan",
        number_type,
        2,
        1,
        fpi=True,
    ) as lib:
        us, faults = lib.fpi_run(GAINS, sp, me)
    _check_trace(us.astype(np.float64), faults.astype(np.int64), ref_u, ref_f, atol=atol)


def _fixed(x: float, scale: float, lo: float, hi: float) -> int:
    """round-half-away(x * scale) saturated to [lo, hi] (NaN -> 0), as documented."""
    v = x * scale
    if math.isnan(v):
        return 0
    if v >= hi:
        return int(hi)
    if v <= lo:
        return int(lo)
    return math.floor(abs(v) + 0.5) * (1 if v >= 0 else -1)


def q15_codes(tab: LookupTable, gains: tuple[float, ...]) -> tuple[int, int, int, int, int]:
    """The header's formulas for the codes ``NAME_fpi_init`` takes, from float32 gains."""
    assert tab.q15 is not None
    kp, ki, kx, u_min, u_max = (float(np.float32(g)) for g in gains)
    big = 2147483647.0
    return (
        _fixed(kp / tab.q15.in_scale[1], 65536.0, -big, big),
        _fixed(ki / tab.q15.in_scale[0], 65536.0, -big, big),
        _fixed(kx * tab.q15.out_scale[0], 65536.0, -big, big),
        _fixed(u_min, 32768.0, -32768.0, 32767.0),
        _fixed(u_max, 32768.0, -32768.0, 32767.0),
    )


def reference_fpi_q15(
    tab: LookupTable, gains: tuple[float, ...], setpoints: np.ndarray, measured: np.ndarray
) -> list[int]:
    """The Q15 fuzzy-PI as the header documents it, with Python integers."""
    kp_q, ki_q, kx_q, lo, hi = q15_codes(tab, gains)
    u = min(max(0, lo), hi)
    e_prev, first = 0, True
    out = []
    for sp, me in zip(setpoints.tolist(), measured.tolist(), strict=True):
        e = int(sp) - int(me)
        de = 0 if first else e - e_prev
        in0 = min(max((ki_q * e + 32768) >> 16, -32768), 32767)
        in1 = min(max((kp_q * de + 32768) >> 16, -32768), 32767)
        y = int(tab.interpolate_q15([np.array([in0]), np.array([in1])])[0][0])
        u = min(max(u + ((kx_q * y + 32768) >> 16), lo), hi)
        e_prev, first = e, False
        out.append(u)
    return out


@needs_cc
@skip_no_cc
def test_c_q15_fpi_is_bit_exact_with_the_documented_integer_loop() -> None:
    tab = table("macvicar_whelan", "q15")
    sp_real, me_real = spring_plant_measurements(table("macvicar_whelan", "double"))
    # Normalised Q15 codes: the NaN/inf samples become a sensor stuck at full scale.
    me_real = np.nan_to_num(me_real, nan=0.99, posinf=0.99)
    sp = np.clip(np.rint(sp_real / 2.5 * 32768), -32768, 32767).astype(np.int16)
    me = np.clip(np.rint(me_real / 2.5 * 32768), -32768, 32767).astype(np.int16)
    gains = (0.8, 1.5, 0.05, -0.3, 0.6)
    ref = reference_fpi_q15(tab, gains, sp, me)
    with CompiledTable(
        sources("macvicar_whelan", "c", "q15"), "macvicar_whelan", "q15", 2, 1, fpi=True
    ) as lib:
        us, faults = lib.fpi_run(q15_codes(tab, gains), sp, me)
    np.testing.assert_array_equal(us.astype(np.int64), ref)
    # the generator's conversion (for --gains) is the documented one
    assert q15_fpi_codes(tab.q15, *gains) == q15_codes(tab, gains)  # type: ignore[arg-type]
    assert not faults.any()
    assert max(ref) == round(0.6 * 32768)  # saturated at u_max
    assert len(set(ref)) > 50  # and it did move
