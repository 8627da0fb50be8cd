"""The certificate against the simulator: over gains (the defaults times 0.25 to 4), stiffness
and latency, on both plants, in the regulation task, count certified cells, simulated-settling
cells, false certificates (certified but not settled) and coverage (certified among settled).

``python -m fuzzkit.analysis.validation`` prints the table docs/stability.md shows.
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
from fuzzkit.analysis.simulated import simulate_cells
from fuzzkit.studies.latency_sweep import scaled_default_gains

FACTORS = (0.25, 0.5, 1.0, 2.0, 4.0)
STIFFNESSES = (5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0)
LATENCIES = ((0, 0), (1, 1), (2, 2), (3, 3), (4, 4))


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
    **certify_options: Any,
) -> tuple[Row, list[dict[str, Any]]]:
    """Certify and simulate every cell for one plant and controller."""
    exp = regulation_experiment()
    detail = []
    for f in factors:
        gains = scaled_default_gains(controller, f)
        region = certify_region(
            exp, controller, plant, stiffnesses, latencies, gains=gains, **certify_options
        )
        outcomes = simulate_cells(
            exp, plant, controller, gains, stiffnesses, latencies, workers=workers
        )
        for cell, out in zip(region.cells, outcomes, strict=True):
            detail.append({"factor": f, **cell.as_dict(), "simulated": out})
    certified = [d for d in detail if d["certified"]]
    settled = [d for d in detail if d["simulated"] == "settled"]
    false = [d for d in certified if d["simulated"] != "settled"]
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
        "| plant | controller | cells | certified | settled in simulation | false certificates "
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
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--detail", help="write every cell as JSON here")
    args = parser.parse_args(argv)
    rows: list[Row] = []
    details: list[dict[str, Any]] = []
    t0 = time.perf_counter()
    for plant in args.plants.split(","):
        for controller in args.controllers.split(","):
            row, detail = compare(plant, controller, workers=args.workers)
            rows.append(row)
            details.extend({"plant": plant, "controller": controller, **d} for d in detail)
            print(f"{plant} {controller}: done ({time.perf_counter() - t0:.0f} s)", file=sys.stderr)
    print(table(rows))
    if args.detail:
        with open(args.detail, "w") as fh:
            json.dump(details, fh, indent=1)
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
