"""The adaptive spec against the best certified fixed gain, on the guarded press (issue 42 item 4).

Per cell (plant, true stiffness, latency): the adaptive spec (``adaptive-pi``, its estimator
knowing the plant's inner loop, :func:`fuzzkit.analysis.estimator_loop.estimating_spec`; its
bands designed from the certificate at the latency, :func:`certified_bands`) runs the
regulation task (a guarded approach below the impact speed, then 12 N held) through the
loop's entry point, on seeds of the sensor noise. The oracle knows the stiffness: it searches
the certificate's grid of fixed gains (the spec's gains without adaptation, times each of
:data:`ORACLE_SCALES`), keeps those ``fuzzkit stability --spec`` certifies in that cell,
simulates them on the same seeds and takes the one of least mean ITAE
(:func:`fuzzkit.studies.tuning.cost.run_itae`).

The cell passes when no adaptive run trips, every one settles within 5 % over its last second
(:func:`settled_within`), and the adaptive mean ITAE is within :data:`ITAE_FACTOR` of the
oracle's. ``python -m fuzzkit.analysis.adaptive_press [--plant P] [--seeds N]`` prints the
table.
"""

from __future__ import annotations

import argparse
import math
from dataclasses import dataclass, replace
from functools import cache

import numpy as np

from fuzzkit.analysis.estimator_loop import SETPOINT_N, estimating_spec
from fuzzkit.analysis.regulation import regulation_experiment
from fuzzkit.analysis.spec_certificate import certify_spec
from fuzzkit.control.adaptation_spec import NONE, Band
from fuzzkit.control.spec import ControllerSpec, with_gains
from fuzzkit.loop.result import RunResult
from fuzzkit.loop.run import run_loop
from fuzzkit.loop.spec import RunSpec
from fuzzkit.studies.experiments import with_spec
from fuzzkit.studies.tuning.cost import run_itae

#: The grid of issue 42 item 4.
PLANTS = ("planar", "arm6", "mujoco")
STIFFNESS = (5.0, 20.0, 100.0, 500.0, 1000.0)
LATENCY = (0, 1, 2, 3)
SEEDS = 10
#: The oracle's candidates: the spec's base gains times each factor (the band scales of the
#: default schedule and the steps between them, 0.01-1).
ORACLE_SCALES = (1.0, 0.7, 0.5, 0.35, 0.2, 0.14, 0.1, 0.07, 0.05, 0.035, 0.02, 0.014, 0.01)
#: The study's schedule before the certificate clips it: the band edges (N/mm) and scales,
#: the kit's default bands with a softer one (scale 1 up to 10 N/mm) in front.
NOMINAL_BANDS = ((1.0, 10.0), (0.5, 30.0), (0.2, 150.0), (0.05, 600.0), (0.02, None))
#: The estimate error each band's scale is certified for (the schedule certificate's default).
BAND_RHO = 0.5
#: The adaptive ITAE may be this many times the oracle's.
ITAE_FACTOR = 2.0
#: "Settled": every true force of the last second within this fraction of the set point.
SETTLE_FRACTION = 0.05
SETTLE_TAIL_S = 1.0


def settled_within(result: RunResult, fraction: float = SETTLE_FRACTION) -> bool:
    """No trip, and every true force on the force axes over the last :data:`SETTLE_TAIL_S`
    within ``fraction`` of its set point."""
    if result.tripped:
        return False
    exp = result.experiment
    tail = result.t >= result.t[-1] - SETTLE_TAIL_S
    for i in range(3):
        if exp.selection[i]:
            sp = float(exp.setpoints[i])
            if float(np.max(np.abs(result.force_true[tail, i] - sp))) > fraction * abs(sp):
                return False
    return True


def fixed_spec(spec: ControllerSpec, scale: float) -> ControllerSpec:
    """``spec`` without adaptation, its lead axis's gains times ``scale`` (``kp``, ``ki`` of a
    PI; ``kx`` of a fuzzy-PI: the factor of the increment either way)."""
    ax = spec.axes[0]
    if spec.kind == "pi":
        gains = {"kp": float(ax.kp or 0.0) * scale, "ki": float(ax.ki or 0.0) * scale}
    else:
        gains = {"kx": float(ax.kx or 0.0) * scale}
    return with_gains(replace(spec, adaptation=NONE), gains)


def run_press(
    spec: ControllerSpec, plant: str, k_n_mm: float, latency: int, seed: int
) -> RunResult:
    """``spec`` on the guarded press at ``k_n_mm``, ``latency`` periods each way."""
    exp = with_spec(regulation_experiment(k_n_mm * 1e3, SETPOINT_N), spec)
    run = RunSpec(exp.name, controller=spec.kind, plant=plant, latency=(latency, latency),
                  seed=seed)  # fmt: skip
    return run_loop(run, exp, plant)


def press_spec(plant: str, latency: int) -> ControllerSpec:
    """The adaptive spec of the study: ``adaptive-pi`` knowing ``plant``'s inner loop
    (:func:`estimating_spec`), its bands :func:`certified_bands` at ``latency``."""
    spec = estimating_spec(plant, 20.0, latency)
    bands = certified_bands(plant, latency)
    return replace(spec, adaptation=replace(spec.adaptation, bands=bands))


@cache
def certified_bands(plant: str, latency: int) -> tuple[Band, ...]:
    """:data:`NOMINAL_BANDS`, each scale lowered to the largest of :data:`ORACLE_SCALES` (at
    most its own) whose fixed gains ``stability --spec`` certifies at the stiffest contact
    that can run the band: the band's top over ``1 - BAND_RHO`` (an estimate that low still
    selects it), at most ``k_max``; the last band at ``k_max``. So the schedule's gain at any
    stiffness is one the certificate proves there, for an estimate within ``BAND_RHO``; a
    band no factor is certified for keeps the smallest."""
    base = estimating_spec(plant, 20.0, latency)
    k_max = base.adaptation.estimator.k_max_n_mm
    out = []
    for scale, up_to in NOMINAL_BANDS:
        worst = k_max if up_to is None else min(up_to / (1.0 - BAND_RHO), k_max)
        allowed = [s for s in certified_scales(plant, worst, latency) if s <= scale]
        out.append(Band(max(allowed, default=min(ORACLE_SCALES)), up_to))
    return tuple(out)


@cache
def certified_scales(plant: str, k_n_mm: float, latency: int) -> tuple[float, ...]:
    """The factors of :data:`ORACLE_SCALES` whose fixed gains ``stability --spec`` certifies
    at this cell."""
    base = estimating_spec(plant, k_n_mm, latency)
    exp = regulation_experiment(k_n_mm * 1e3, SETPOINT_N)
    out = []
    for s in ORACLE_SCALES:
        region = certify_spec(exp, fixed_spec(base, s), plant, [k_n_mm], [(latency, latency)])
        if region.cells[0].certified:
            out.append(s)
    return tuple(out)


@dataclass(frozen=True, slots=True)
class PressCell:
    """One cell: the adaptive runs' trips, settled count and mean ITAE; the oracle's factor and
    mean ITAE (NaN, None: no certified fixed gain)."""

    plant: str
    k_n_mm: float
    latency: int
    seeds: int
    trips: int
    settled: int
    itae: float
    oracle_scale: float | None
    oracle_itae: float
    certified_scales: tuple[float, ...]

    @property
    def ratio(self) -> float:
        """Adaptive ITAE over the oracle's (NaN without an oracle)."""
        return self.itae / self.oracle_itae if self.oracle_scale is not None else math.nan

    @property
    def passed(self) -> bool:
        """No trip, every run settled, ITAE within :data:`ITAE_FACTOR` of the oracle's."""
        return (
            self.trips == 0
            and self.settled == self.seeds
            and math.isfinite(self.ratio)
            and self.ratio <= ITAE_FACTOR
        )


def press_cell(plant: str, k_n_mm: float, latency: int, seeds: int = SEEDS) -> PressCell:
    """Run one cell (module docstring)."""
    spec = press_spec(plant, latency)
    runs = [run_press(spec, plant, k_n_mm, latency, s) for s in range(seeds)]
    itae = float(np.mean([run_itae(r) for r in runs]))
    scales = certified_scales(plant, k_n_mm, latency)
    best_scale, best = None, math.inf
    for s in scales:
        fixed = fixed_spec(spec, s)
        value = float(np.mean([run_itae(run_press(fixed, plant, k_n_mm, latency, seed))
                               for seed in range(seeds)]))  # fmt: skip
        if value < best:
            best_scale, best = s, value
    return PressCell(
        plant, k_n_mm, latency, seeds,
        trips=sum(r.tripped for r in runs),
        settled=sum(settled_within(r) for r in runs),
        itae=itae,
        oracle_scale=best_scale,
        oracle_itae=best if best_scale is not None else math.nan,
        certified_scales=scales,
    )  # fmt: skip


def table(cells: list[PressCell]) -> str:
    """The cells as a Markdown table."""
    head = ("plant", "k (N/mm)", "latency", "trips", "settled", "ITAE", "oracle factor",
            "oracle ITAE", "ratio", "pass")  # fmt: skip
    rows = [
        (c.plant, f"{c.k_n_mm:g}", f"{c.latency}:{c.latency}", str(c.trips),
         f"{c.settled}/{c.seeds}", f"{c.itae:.4f}",
         "none certified" if c.oracle_scale is None else f"{c.oracle_scale:g}",
         f"{c.oracle_itae:.4f}", f"{c.ratio:.2f}", "yes" if c.passed else "no")
        for c in cells
    ]  # fmt: skip
    return "\n".join("| " + " | ".join(r) + " |" for r in (head, ("---",) * len(head), *rows))


def main(argv: list[str] | None = None) -> int:
    """Print the table (``--plant``: some plants; ``--seeds``: fewer seeds)."""
    parser = argparse.ArgumentParser(prog="python -m fuzzkit.analysis.adaptive_press")
    parser.add_argument("--plant", choices=PLANTS, action="append", help="plants (default: all)")
    parser.add_argument("--seeds", type=int, default=SEEDS, help=f"seeds (default {SEEDS})")
    args = parser.parse_args(argv)
    cells = []
    for plant in args.plant or PLANTS:
        for k in STIFFNESS:
            for lat in LATENCY:
                cells.append(press_cell(plant, k, lat, args.seeds))
                c = cells[-1]
                print(f"{plant} {k:g} {lat}:{lat}: ratio {c.ratio:.2f} trips {c.trips} "
                      f"settled {c.settled}/{c.seeds}", flush=True)  # fmt: skip
    print(table(cells))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
