"""Issue 42 item 1: the stiffness estimator in the closed loop (not on an imposed excitation).

The adaptive controller runs the regulation task (a guarded approach below the impact speed,
then 12 N held) on the planar and arm6 plants through the loop's entry point, its estimator
knowing the plant's identified inner loop (:mod:`fuzzkit.analysis.estimator_loop`). The truth is
the scenario's contact stiffness, not anything the estimator computes. ``make test`` runs four
cells covering every plant, stiffness decade, latency and noise level between them; ``make
verify`` the whole 5-1000 N/mm x latency 0:0-3:3 x noise 0.05-0.1 N grid.
"""

from __future__ import annotations

import pytest

from fuzzkit.analysis.estimator_loop import (
    LATENCY,
    NOISE,
    QUICK,
    STIFFNESS,
    estimate_in_loop,
    estimating_spec,
)
from fuzzkit.control.adaptation_spec import IDENTIFIED_INNER_LOOPS

#: The issue's target: the final estimate within this factor of the truth.
RHO = 1.5
#: The least number of periods in which the estimate moved (measured: 2 on planar at 1000 N/mm,
#: latency 0:0, noise 0.1 N, where the loop settles within a few periods; 4-615 elsewhere).
EXCITED = 2


@pytest.mark.parametrize("plant", sorted(IDENTIFIED_INNER_LOOPS))
def test_the_estimator_knows_the_inner_loop_of_its_plant(plant: str) -> None:
    est = estimating_spec(plant, 20.0, 1).adaptation.estimator
    assert (est.inner_q, est.inner_a, est.inner_g) == IDENTIFIED_INNER_LOOPS[plant]
    assert est.delay_periods == 1 + 2  # 1 + the loop's latency, sensor + command


@pytest.mark.parametrize(("plant", "k_n_mm", "latency", "noise_n"), QUICK)
def test_the_closed_loop_estimate_ends_within_rho(
    plant: str, k_n_mm: float, latency: int, noise_n: float
) -> None:
    run = estimate_in_loop(plant, k_n_mm, latency, noise_n)
    assert run.excited >= EXCITED
    assert run.ratio <= RHO, run


@pytest.mark.verify
@pytest.mark.parametrize("plant", sorted(IDENTIFIED_INNER_LOOPS))
def test_the_closed_loop_estimate_ends_within_rho_on_the_whole_grid(plant: str) -> None:
    bad = []
    for k in STIFFNESS:
        for lat in LATENCY:
            for noise in NOISE:
                run = estimate_in_loop(plant, k, lat, noise)
                if run.ratio > RHO or run.excited < EXCITED:
                    bad.append(run)
    assert not bad, bad


#: Where the MuJoCo arm's contact is softer than its servo (k_s = 173 N/mm, docs/stability.md):
#: there the force answers a correction with about the contact's own stiffness. Stiffer, it
#: answers with ``k k_s / (k + k_s)`` (at most 173 N/mm), which is what the estimate finds
#: (docs/controller.md); the target is not met there.
MUJOCO_OBSERVABLE = (5.0, 20.0)


@pytest.mark.verify
def test_the_closed_loop_estimate_ends_within_rho_on_mujoco_below_its_servo_stiffness() -> None:
    bad = []
    for k in MUJOCO_OBSERVABLE:
        for lat in LATENCY:
            for noise in NOISE:
                run = estimate_in_loop("mujoco", k, lat, noise)
                if run.ratio > RHO or run.excited < EXCITED:
                    bad.append(run)
    assert not bad, bad
