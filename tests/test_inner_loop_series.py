"""The inner loop's series compliance: a servo that gives way under the contact force
(MuJoCo's PD joints) reaches only ``k_s / (k + k_s)`` of a commanded indentation, held still,
against a contact of stiffness ``k`` (issue 40 item 5)."""

from __future__ import annotations

import pytest

from fuzzkit.analysis.inner_loop import (
    SERIES_THRESHOLD,
    InnerFit,
    InnerLoop,
    identify,
    press_gain,
    series_gain,
    series_stiffness,
)
from fuzzkit.analysis.region import axis_loop
from fuzzkit.analysis.regulation import regulation_experiment


def test_series_stiffness_is_recovered_from_exact_static_gains() -> None:
    ks = 173.0e3
    gains = {k: ks / (k + ks) for k in (5e3, 1e5, 1e6)}
    assert series_stiffness(gains) == pytest.approx(ks, rel=1e-12)
    assert series_gain(ks, 1e6) == pytest.approx(173.0 / 1173.0, rel=1e-12)
    assert series_gain(None, 1e6) == 1.0


def test_a_loss_below_the_threshold_is_no_series_term() -> None:
    # the planar arm loses 0.4 % at 1000 N/mm: inside its g interval, not modelled apart
    assert series_stiffness({5e3: 0.9998, 1e6: 1.0 - 0.4 * SERIES_THRESHOLD}) is None
    assert series_stiffness({5e3: 0.9998, 1e6: 1.0 - 2.0 * SERIES_THRESHOLD}) is not None


def test_mujocos_press_at_an_unfitted_stiffness_follows_the_series_law() -> None:
    # k_s from presses at 100 and 1000 N/mm predicts the press at 300 N/mm (measured 0.3663)
    ks = series_stiffness({k: press_gain("mujoco", k) for k in (1e5, 1e6)})
    assert ks is not None and 150e3 < ks < 200e3
    assert press_gain("mujoco", 3e5) == pytest.approx(series_gain(ks, 3e5), rel=2e-3)


def test_arm6_has_no_series_compliance() -> None:
    assert press_gain("arm6", 1e6) == pytest.approx(1.0, abs=1e-4)


def test_the_certificate_reads_the_gain_at_the_cells_stiffness() -> None:
    fit = InnerFit(1e5, 0.5, 1.0, 0.0, 0.5)
    inner = InnerLoop("x", (fit,), (0.5, 0.5), (0.9, 1.1), (0.5, 0.5), series_n_per_m=173e3)
    exp = regulation_experiment()
    for k in (5e3, 1e6):
        loop = axis_loop(exp, "pi", None, inner, None, k, (0, 0))
        s = 173e3 / (k + 173e3)
        assert loop.inner_g == pytest.approx((0.9 * s, 1.1 * s), rel=1e-12)


@pytest.mark.verify
@pytest.mark.parametrize("plant", ["mujoco", "mujoco-elastic"])
def test_the_identified_series_stiffness_predicts_presses_it_was_not_fitted_on(plant) -> None:
    inner = identify(plant)
    assert inner.series_n_per_m is not None
    for k in (2e4, 3e5):
        assert press_gain(plant, k) == pytest.approx(series_gain(inner.series_n_per_m, k), rel=5e-3)


def test_the_stability_text_states_the_series_stiffness() -> None:
    from fuzzkit.cli.stability import series_text

    assert series_text(None) == ""
    assert "servo stiffness 173.4 N/mm in series" in series_text(173.44)
