"""The certificate against the simulator: over gains, stiffness and latency, on both plants, in
the regulation task, count certified cells, cells that settle in every noise seed, false
certificates (certified, but some seed did not settle) and coverage (certified among settled).

Two grids, disjoint in every coordinate: :data:`CALIBRATION` (the defaults times 0.25 to 4,
the grid on which the planar contact-lag interval was calibrated) and :data:`VALIDATION`
(other gain factors, stiffnesses and latencies, never used to choose anything in the model).

``python -m fuzzkit.analysis.validation`` prints both tables docs/stability.md shows.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from fuzzkit.analysis.region import certify_region
from fuzzkit.analysis.regulation import regulation_experiment
from fuzzkit.analysis.simulated import simulated_runs, worst_outcome
from fuzzkit.studies.latency_sweep import scaled_default_gains
from fuzzkit.studies.outcome import SETTLED

#: The sensor-noise seeds every cell is simulated with; a cell settles when it settles in all.
SEEDS = (0, 1, 2)


@dataclass(frozen=True, slots=True)
class Grid:
    """Gain factors (on the defaults' loop gain) x stiffnesses (N/mm) x latencies."""

    name: str
    factors: tuple[float, ...]
    stiffnesses: tuple[float, ...]
    latencies: tuple[tuple[int, int], ...]

    @property
    def cells(self) -> int:
        """Cells per plant and controller."""
        return len(self.factors) * len(self.stiffnesses) * len(self.latencies)


#: The grid the planar contact-lag interval was calibrated on (docs/stability.md).
CALIBRATION = Grid(
    "calibration",
    (0.25, 0.5, 1.0, 2.0, 4.0),
    (5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0),
    ((0, 0), (1, 1), (2, 2), (3, 3), (4, 4)),
)
#: A grid sharing no gain factor, stiffness or latency with :data:`CALIBRATION`.
VALIDATION = Grid(
    "validation",
    (0.35, 0.7, 1.4, 2.8),
    (7.0, 15.0, 30.0, 70.0, 150.0, 300.0, 700.0),
    ((0, 1), (1, 0), (1, 2), (2, 3), (3, 1)),
)
GRIDS = {g.name: g for g in (CALIBRATION, VALIDATION)}
FACTORS = CALIBRATION.factors
STIFFNESSES = CALIBRATION.stiffnesses
LATENCIES = CALIBRATION.latencies


@dataclass(frozen=True, slots=True)
class Row:
    """One (plant, controller) line of the table."""

    plant: str
    controller: str
    cells: int
    certified: int
    settled: int
    false_certificates: int
    covered: int
    false_cases: tuple[dict[str, Any], ...]

    @property
    def coverage(self) -> float:
        """Certified share of the settling cells."""
        return self.covered / self.settled if self.settled else float("nan")


def compare(
    plant: str,
    controller: str,
    factors: Sequence[float] = FACTORS,
    stiffnesses: Sequence[float] = STIFFNESSES,
    latencies: Sequence[tuple[int, int]] = LATENCIES,
    workers: int | None = 2,
    seeds: Sequence[int] = SEEDS,
    **certify_options: Any,
) -> tuple[Row, list[dict[str, Any]]]:
    """Certify and simulate (every seed) every cell for one plant and controller."""
    exp = regulation_experiment()
    detail = []
    for f in factors:
        gains = scaled_default_gains(controller, f)
        region = certify_region(
            exp, controller, plant, stiffnesses, latencies, gains=gains, **certify_options
        )
        per_seed = simulated_runs(
            exp, plant, controller, gains, stiffnesses, latencies, seeds, workers=workers
        )
        for i, cell in enumerate(region.cells):
            runs = [outs[i].outcome for outs in per_seed]
            detail.append(
                {
                    "factor": f,
                    **cell.as_dict(),
                    "simulated": worst_outcome(runs),
                    "simulated_per_seed": dict(zip(map(str, seeds), runs, strict=True)),
                }
            )
    certified = [d for d in detail if d["certified"]]
    settled = [d for d in detail if d["simulated"] == SETTLED]
    false = [d for d in certified if d["simulated"] != SETTLED]
    row = Row(
        plant,
        controller,
        len(detail),
        len(certified),
        len(settled),
        len(false),
        sum(1 for d in settled if d["certified"]),
        tuple(false),
    )
    return row, detail


def table(rows: Sequence[Row]) -> str:
    """The Markdown table of docs/stability.md."""
    out = [
        "| plant | controller | cells | certified | settled in every seed | false certificates "
        "| coverage (certified / settled) |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        out.append(
            f"| {r.plant} | {r.controller} | {r.cells} | {r.certified} | {r.settled} | "
            f"{r.false_certificates} | {r.covered} / {r.settled} = {100 * r.coverage:.0f} % |"
        )
    return "\n".join(out)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the comparison on both plants and controllers and print the table."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--plants", default="planar,arm6")
    parser.add_argument("--controllers", default="pi,fuzzy-pi")
    parser.add_argument("--grids", default="calibration,validation")
    parser.add_argument("--seeds", type=int, default=len(SEEDS), help="noise seeds 0..N-1")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--detail", help="write every cell as JSON here")
    args = parser.parse_args(argv)
    details: list[dict[str, Any]] = []
    t0 = time.perf_counter()
    for grid_name in args.grids.split(","):
        grid = GRIDS[grid_name]
        rows: list[Row] = []
        for plant in args.plants.split(","):
            for controller in args.controllers.split(","):
                row, detail = compare(
                    plant,
                    controller,
                    grid.factors,
                    grid.stiffnesses,
                    grid.latencies,
                    workers=args.workers,
                    seeds=tuple(range(args.seeds)),
                )
                rows.append(row)
                details.extend(
                    {"grid": grid.name, "plant": plant, "controller": controller, **d}
                    for d in detail
                )
                print(
                    f"{grid.name} {plant} {controller}: done ({time.perf_counter() - t0:.0f} s)",
                    file=sys.stderr,
                    flush=True,
                )
        print(f"{grid.name} grid ({args.seeds} seeds per cell):")
        print(table(rows), flush=True)
    if args.detail:
        with open(args.detail, "w") as fh:
            json.dump(details, fh, indent=1)
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
