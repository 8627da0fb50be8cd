"""``fuzzkit tune`` (optimal gains to a gains file) and ``fuzzkit report`` (PI vs fuzzy-PI)."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any

from fuzzkit.errors import ConfigError
from fuzzkit.fileio import check_output_path

CONTROLLERS = ("pi", "fuzzy-pi")


def register(subparsers: Any) -> None:
    """Add the ``tune`` and ``report`` subcommands."""
    from fuzzkit.studies.plants import PLANTS

    tune = subparsers.add_parser(
        "tune",
        help="find optimal gains (Kp, Ki, Kx) by simulation and write a gains file",
        description=(
            "Minimise the closed-loop cost (ITAE of the force error plus penalties for "
            "overshoot, force above the safety limit and contact loss; see fuzzkit.studies.tuning) "
            "over the experiments and stiffnesses given, by differential evolution and a "
            "local polish. Ctrl-C stops early and still writes the best gains so far."
        ),
    )
    tune.add_argument("experiments", nargs="+", metavar="EXPERIMENT", help="E1, E2, E3")
    tune.add_argument("--controller", choices=CONTROLLERS, default="fuzzy-pi")
    tune.add_argument(
        "--rulebase", default="macvicar_whelan", metavar="RB", help="shipped name or YAML path"
    )
    tune.add_argument("--plant", choices=sorted(PLANTS), default="planar")
    tune.add_argument(
        "--stiffness",
        default="5,10,20",
        metavar="K1,K2,..",
        help="environment stiffnesses to tune over at once, N/mm (default 5,10,20)",
    )
    tune.add_argument(
        "--budget", type=int, default=120, help="most gain sets simulated (default 120)"
    )
    tune.add_argument("--seed", type=int, default=0, help="optimiser seed (default 0)")
    tune.add_argument(
        "--workers", type=int, default=None, help="worker processes (default: every core)"
    )
    tune.add_argument(
        "--latency",
        default="0:0",
        metavar="S:C[,S:C...]",
        help="sensor:command delays in periods to tune over at once (default 0:0)",
    )
    tune.add_argument(
        "--loop",
        choices=("compiled", "python"),
        default=None,
        help="default: the compiled loop where the plant has one (arm6)",
    )
    tune.add_argument(
        "--scheduler",
        default=None,
        metavar="ADDRESS",
        help="dask.distributed scheduler (tcp://host:8786): price the candidates on its workers",
    )
    tune.add_argument("--out", required=True, metavar="GAINS.yaml", help="gains file to write")
    tune.add_argument(
        "--replace",
        action="store_true",
        help="overwrite --out (default: keep the other controller's entry if the file has one)",
    )
    tune.add_argument("--quiet", action="store_true", help="no progress bar")
    tune.set_defaults(handler=_tune)

    rep = subparsers.add_parser(
        "report",
        help="run E1-E3 x {PI, fuzzy-PI} x {default, tuned gains}; write report.md + figures",
        description=(
            "Write DIR/report.md with force plots, the control surface, the stiffness study, "
            "the comparison table and the paper's claims checked against the numbers, plus "
            "one .rrd per run. Tunes both controllers with a small budget unless --gains-dir "
            "holds pi.yaml and fuzzy-pi.yaml."
        ),
    )
    rep.add_argument("--out", required=True, metavar="DIR", help="output folder")
    rep.add_argument("--plant", choices=[*sorted(PLANTS), "both"], default="planar")
    rep.add_argument(
        "--budget", type=int, default=40, help="tuning budget per controller (default 40)"
    )
    rep.add_argument("--gains-dir", metavar="DIR", help="folder with pi.yaml and fuzzy-pi.yaml")
    rep.add_argument("--rulebase", default="macvicar_whelan", metavar="RB")
    rep.add_argument("--seed", type=int, default=0)
    rep.add_argument("--workers", type=int, default=None)
    rep.add_argument("--no-rrd", action="store_true", help="skip the .rrd recordings")
    rep.add_argument("--quiet", action="store_true", help="no progress output")
    rep.set_defaults(handler=_report)


def parse_stiffness(text: str) -> tuple[float, ...]:
    """Parse ``"10,100,1000"`` (N/mm) into floats.

    Raises
    ------
    ConfigError
        An item that is not a positive finite number, or an empty list.
    """
    out: list[float] = []
    for item in text.split(","):
        item = item.strip()
        try:
            k = float(item)
        except ValueError:
            raise ConfigError(
                f"--stiffness: {item!r} is not a number (expected N/mm values like 5,10,20)"
            ) from None
        if not (math.isfinite(k) and k > 0.0):
            raise ConfigError(f"--stiffness: {item!r} must be a positive stiffness in N/mm")
        out.append(k)
    if not out:
        raise ConfigError("--stiffness: no values (expected N/mm values like 5,10,20)")
    return tuple(out)


def _tune(args: argparse.Namespace) -> int:
    from fuzzkit.cli.sweep import parse_latencies
    from fuzzkit.control.gains import read_gains_file, write_gains
    from fuzzkit.studies.tuning import ProgressBar, tune

    ks = parse_stiffness(args.stiffness)
    latencies = parse_latencies(args.latency)
    out = Path(args.out)
    check_output_path(out, "gains file")
    if out.is_file() and not args.replace:
        read_gains_file(out)  # an unreadable existing file is reported now, not after tuning
    bar = None if args.quiet else ProgressBar()
    result = tune(
        args.experiments,
        args.controller,
        args.rulebase,
        args.plant,
        ks,
        budget=args.budget,
        seed=args.seed,
        workers=args.workers,
        callback=bar,
        latencies=latencies,
        loop=args.loop or "auto",
        scheduler=args.scheduler,
    )
    if bar is not None:
        bar.done()
    _, kept = write_gains(out, result.to_entry(), merge=not args.replace)
    print(
        f"tuned {result.controller} on {' '.join(result.experiments)} ({result.plant}, "
        f"{'/'.join(f'{k:g}' for k in ks)} N/mm): {result.evaluations} evaluations in "
        f"{result.wall_time_s:.1f} s"
        + (" (interrupted: best so far)" if result.interrupted else "")
    )
    print(
        f"  cost {result.cost:.6g} vs default gains {result.baseline_cost:.6g} "
        f"({-result.improvement_pct:+.1f} %)"
    )
    for name, c in result.experiment_costs.items():
        print(f"  {name}: {c:.6g} (default {result.baseline_experiment_costs[name]:.6g})")
    gains = ", ".join(f"{k}={v:.6g}" for k, v in result.gains.items())
    print(f"  gains: {gains}")
    print(f"wrote {out}" + (f" (kept the {', '.join(kept)} entry)" if kept else ""))
    return 130 if result.interrupted else 0


def _report(args: argparse.Namespace) -> int:
    from fuzzkit.report.build import build_report

    if args.budget < 10:
        raise ConfigError(f"--budget must be >= 10 (got {args.budget})")
    plants = ["planar", "arm6"] if args.plant == "both" else [args.plant]
    path = build_report(
        Path(args.out),
        plants=plants,
        budget=args.budget,
        gains_dir=Path(args.gains_dir) if args.gains_dir else None,
        rulebase=args.rulebase,
        seed=args.seed,
        workers=args.workers,
        rrd=not args.no_rrd,
        log=None if args.quiet else sys.stderr,
    )
    print(f"wrote {path}")
    return 0
