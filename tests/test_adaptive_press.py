"""Issue 42 item 4: the adaptive spec on the guarded press against the best certified fixed gain
of each cell (:mod:`fuzzkit.analysis.adaptive_press`).

The oracle is independent of the adaptation: fixed gains, certified by ``stability --spec`` at
the cell (the certificate, not the schedule, decides which it may use) and simulated on the
same seeds. ``make test`` runs two cells at 2 seeds; ``make verify`` the planar and arm6 cells
the docs' table says pass, at 2 seeds.
"""

from __future__ import annotations

import pytest
from _pairwise import verify

from fuzzkit.analysis.adaptive_press import (
    ITAE_FACTOR,
    NOMINAL_BANDS,
    ORACLE_SCALES,
    certified_bands,
    certified_scales,
    estimating_spec,
    fixed_spec,
    press_cell,
    run_press,
    settled_within,
)

#: (plant, k N/mm, latency): the cells of make test, then of make verify (docs/controller.md,
#: "Adaptive against the best certified fixed gain": the cells that pass there).
CELLS = [
    ("arm6", 20.0, 0),
    ("planar", 500.0, 1),
    pytest.param("planar", 100.0, 0, marks=verify),
    pytest.param("arm6", 100.0, 1, marks=verify),
    pytest.param("planar", 1000.0, 0, marks=verify),
]


@pytest.mark.parametrize(("plant", "k_n_mm", "latency"), CELLS)
def test_the_adaptive_press_is_within_twice_the_best_certified_fixed_gain(
    plant: str, k_n_mm: float, latency: int
) -> None:
    cell = press_cell(plant, k_n_mm, latency, seeds=2)
    assert cell.trips == 0 and cell.settled == 2
    assert cell.oracle_scale in cell.certified_scales
    assert cell.ratio <= ITAE_FACTOR, cell


def test_the_oracle_searches_only_certified_gains() -> None:
    """At 500 N/mm, latency 1:1 on planar the certificate refuses the larger factors: the
    oracle's candidates are a tail of the grid, and a refused one is hotter than every
    certified one (the loop gain grows with the factor)."""
    scales = certified_scales("planar", 500.0, 1)
    assert scales and scales != ORACLE_SCALES
    refused = [s for s in ORACLE_SCALES if s not in scales]
    assert min(refused) > max(scales)
    assert press_cell("planar", 500.0, 1, seeds=1).oracle_scale in scales


def test_the_studys_bands_are_certified_at_the_stiffest_contact_each_can_run() -> None:
    """Each band's scale is one the certificate proves at the band's top over 1 - rho (k_max
    for the last), and no larger nominal one would be: at 3:3 the stiff bands are lowered."""
    nominal = dict((up, s) for s, up in NOMINAL_BANDS)
    for band in certified_bands("planar", 3):
        worst = 2000.0 if band.up_to_n_mm is None else min(band.up_to_n_mm / 0.5, 2000.0)
        scales = certified_scales("planar", worst, 3)
        allowed = [s for s in scales if s <= nominal[band.up_to_n_mm]]
        # none certified (k_max = 2000 N/mm at 3:3 on planar): the smallest of the grid
        assert band.scale == max(allowed, default=min(ORACLE_SCALES))
    assert certified_bands("planar", 3)[-2].scale < nominal[600.0]


def test_settled_within_is_the_band_over_the_last_second() -> None:
    spec = estimating_spec("arm6", 20.0, 0)
    run = run_press(fixed_spec(spec, 0.35), "arm6", 20.0, 0, 0)
    assert settled_within(run)
    # the same run judged against a band far tighter than its noise-free end: refused
    assert not settled_within(run, fraction=1e-9)
