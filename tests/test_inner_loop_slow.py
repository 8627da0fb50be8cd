"""The inner loop with a slow lag, local in stiffness (issue 40 item 5): MuJoCo's servo
overshoots (its fast gain ``h`` above the static one) and creeps back through its gear friction
(a slow lag of gain ``1 - h``), and both change with the contact's stiffness."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fuzzkit.analysis.inner_loop import (
    InnerFit,
    InnerLoop,
    bracket,
    excite,
    fit_slow,
    identify,
    series_gain,
    simulate_slow,
)
from fuzzkit.analysis.loop_model import AxisLoop, closed_loop_matrix, vertex_matrices


def _recursion(r: np.ndarray, a: float, q: float, h: float, b: float) -> np.ndarray:
    """The cascade written out period by period, from rest at r[0]."""
    x = p = y = 0.0
    out = np.empty(len(r))
    for k in range(len(r)):
        d = r[k] - r[0]
        x = q * x + (1.0 - q) * d
        p = a * p + (1.0 - a) * h * x
        y = b * y + (1.0 - b) * (1.0 - h) * x
        out[k] = r[0] + p + y
    return out


def _prbs(n: int = 600, seed: int = 3) -> np.ndarray:
    rng = np.random.default_rng(seed)
    level = np.repeat(np.where(rng.integers(0, 2, n) > 0, 1.0, -1.0), rng.integers(1, 20, n))
    return np.concatenate([[0.0], level[: n - 1]])


def test_the_slow_cascade_is_its_recursion() -> None:
    r = _prbs()
    assert np.allclose(simulate_slow(r, 0.6, 0.5, 2.5, 0.9), _recursion(r, 0.6, 0.5, 2.5, 0.9))


def test_the_fit_recovers_a_known_cascade() -> None:
    r = _prbs()
    p = _recursion(r, 0.55, 0.6, 3.0, 0.92)
    fit = fit_slow(r, p, 1e5)
    assert fit.nrmse < 1e-6
    assert (fit.a, fit.q) == pytest.approx((0.55, 0.6), abs=1e-4) or (
        fit.a,
        fit.q,
    ) == pytest.approx((0.6, 0.55), abs=1e-4)  # the two fast lags commute
    assert fit.h == pytest.approx(3.0, rel=1e-4) and fit.b == pytest.approx(0.92, abs=1e-5)


def _loop(**kw: object) -> AxisLoop:
    base: dict[str, object] = dict(
        period_s=0.004,
        stiffness_n_per_m=1e5,
        damping_n_s_per_m=100.0,
        sensor_delay=1,
        command_delay=1,
        filter_cutoff_hz=60.0,
        kp=2e-6,
        ki=1e-6,
        inner_a=(0.5, 0.6),
        inner_g=(0.6, 0.7),
        inner_q=(0.5, 0.6),
        inner_b=(0.8, 0.95),
        inner_h=(1.5, 2.5),
    )
    base.update(kw)
    return AxisLoop(**base)  # type: ignore[arg-type]


@pytest.mark.parametrize("name", ["a", "g", "q", "b", "h"])
def test_the_loop_matrix_is_affine_in_the_slow_lags_parameters(name: str) -> None:
    loop = _loop()
    base = {"sigma": 1.0, "phi": 1.0, "a": 0.55, "g": 0.65, "q": 0.5, "b": 0.9, "h": 2.0}

    def at(value: float) -> np.ndarray:
        return closed_loop_matrix(loop, **{**base, name: value})  # type: ignore[arg-type]

    lo, hi, t = 0.3, 0.9, 0.37
    assert np.allclose(at(t * hi + (1 - t) * lo), t * at(hi) + (1 - t) * at(lo), atol=1e-12)


def test_without_an_overshoot_the_slow_lag_is_decoupled() -> None:
    # h = g: the slow lag gets no input; the loop's other poles are the two-lag model's
    slow, plain = _loop(), _loop(inner_b=None, inner_h=None)
    a_slow = closed_loop_matrix(slow, 1.0, 1.0, 0.55, 0.65, None, 0.5, 0.0, 0.9, 0.65)
    a_plain = closed_loop_matrix(plain, 1.0, 1.0, 0.55, 0.65, None, 0.5, 0.0)
    ev_slow = np.sort_complex(np.linalg.eigvals(a_slow))
    ev_plain = np.sort_complex(np.concatenate([np.linalg.eigvals(a_plain), [0.9]]))
    assert np.allclose(ev_slow, ev_plain, atol=1e-9)
    assert slow.order == plain.order + 1
    assert len(vertex_matrices(slow)) == 4 * len(vertex_matrices(plain))


def test_a_cell_reads_the_fits_either_side_of_its_stiffness() -> None:
    fits = tuple(
        InnerFit(k, a, 1.0, 0.1, a, b=b, h=h)
        for k, a, b, h in ((1e4, 0.5, 0.9, 2.0), (1e5, 0.6, 0.8, 3.0), (1e6, 0.7, 0.7, 4.0))
    )
    inner = InnerLoop("x", fits, (0.0, 1.0), (0.9, 1.1), (0.0, 1.0), series_n_per_m=173e3)
    assert [f.stiffness_n_per_m for f in bracket(fits, 3e4)] == [1e4, 1e5]
    assert [f.stiffness_n_per_m for f in bracket(fits, 1e5)] == [1e5]
    assert [f.stiffness_n_per_m for f in bracket(fits, 5e6)] == [1e6]
    lo, hi = inner.at(3e4)  # one box per neighbour, each with its own fit error
    s = series_gain(173e3, 3e4)
    assert lo.a == pytest.approx((0.4, 0.6)) and hi.a == pytest.approx((0.5, 0.7))
    assert lo.h == pytest.approx((2.0 * 0.9 * s, 2.0 * 1.1 * s))
    assert hi.g == pytest.approx((0.9 * s, 1.1 * s))
    # the slow lag's time constant widened by 1 +- 0.1
    tau = -1.0 / math.log(0.9)
    assert lo.b == pytest.approx((math.exp(-1.0 / (tau / 1.1)), math.exp(-1.0 / (tau * 1.1))))
    assert len(inner.at(1e5)) == 1


@pytest.mark.verify
def test_mujocos_local_model_describes_a_stiffness_it_was_not_identified_at() -> None:
    # 30 N/mm lies between the identification points 20 and 50 N/mm: the model of either
    # neighbour, run on the excitation at 30 N/mm, is within the carried fit error
    inner = identify("mujoco")
    r, p = excite("mujoco", 3e4)
    p = p / series_gain(inner.series_n_per_m, 3e4)
    for f in bracket(inner.fits, 3e4):
        assert f.b is not None and f.h is not None
        model = simulate_slow(r, f.a, f.q, f.h, f.b)
        err = np.sqrt(np.mean((model - np.mean(model) - p + np.mean(p)) ** 2)) / np.std(p)
        assert err < 0.25, (f.stiffness_n_per_m, err)
