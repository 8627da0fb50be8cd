"""``fuzzkit sweep``: the cartesian product of experiments, controllers, stiffnesses, latencies,
gains and noise seeds, run in batch (all local cores, or a Dask cluster) into one tidy table."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from fuzzkit.cli import (
    EXIT_TRIPPED,
    RULEBASE_SPEC_HELP,
    add_controller_impl_argument,
    add_plant_argument,
    numbers,
)
from fuzzkit.cli import units as cli_units
from fuzzkit.cli.simulation import FAIL_ON_TRIP_HELP
from fuzzkit.control.names import RUN_CONTROLLERS
from fuzzkit.errors import ConfigError


def register(subparsers: Any) -> None:
    """Add the ``sweep`` subcommand."""
    p = subparsers.add_parser(
        "sweep",
        help="run the cartesian product of experiments and parameters into one table",
        description=(
            "Run every combination of experiment x controller x stiffness x latency x gains x "
            "seed and write one row per run (every parameter, every metric of simulate --json) "
            "as CSV or Parquet, plus a summary figure. Uses all local cores, or the Dask "
            "cluster at --scheduler."
        ),
        epilog="examples:\n"
        "  fuzzkit sweep E1 E2 --stiffness 5,10,20 --latency 0:0,2:1 --seeds 3 --out runs.csv\n"
        "  fuzzkit sweep E2 --controller pi --scheduler tcp://127.0.0.1:8786 --out runs.parquet\n"
        "  fuzzkit sweep ./my_task.yaml --seeds 4 --out runs.csv --png-dir runs/",
    )
    p.add_argument(
        "experiments",
        nargs="+",
        metavar="EXPERIMENT",
        help="E1, E2, E3 (shipped scenarios) or scenario files TASK.yaml",
    )
    p.add_argument(
        "--controller",
        default="pi,fuzzy-pi",
        help="comma list of pi, fuzzy-pi, adaptive-pi, adaptive-fuzzy-pi (default pi,fuzzy-pi)",
    )
    p.add_argument(
        "--stiffness",
        type=cli_units.stiffnesses,
        default=None,
        metavar=cli_units.STIFFNESSES_METAVAR,
        help=f"environment stiffnesses ({cli_units.STIFFNESS_HELP}; default: each "
        "experiment's own)",
    )
    p.add_argument(
        "--latency",
        type=cli_units.latencies,
        default=None,
        metavar=cli_units.LATENCIES_METAVAR,
        help=f"{cli_units.LATENCY_HELP} (default: each experiment's own)",
    )
    p.add_argument("--seeds", type=numbers.SEEDS, default=1, metavar="N", help="noise seeds 0..N-1")
    p.add_argument(
        "--gains",
        default=None,
        metavar="FILE[,FILE...]",
        help="gains files to compare (each one a value of the sweep); default gains otherwise",
    )
    p.add_argument(
        "--spec",
        default=None,
        metavar="SPEC[,SPEC...]",
        help="controller specs (docs/controller.md) to compare, each a value of the sweep in "
        "place of --controller (a spec holds its gains: not with --gains)",
    )
    add_plant_argument(p, "simulated robot, as simulate, tune and report")
    p.add_argument(
        "--rulebase",
        default="macvicar_whelan",
        metavar="RB",
        help="rule base for fuzzy-pi: " + RULEBASE_SPEC_HELP,
    )
    p.add_argument(
        "--loop",
        choices=("compiled", "python"),
        default=None,
        help="default: compiled where the plant supports it and the controller is the "
        "generated C (--controller-impl auto or c)",
    )
    add_controller_impl_argument(p)
    p.add_argument(
        "--duration",
        type=numbers.DURATION_S,
        default=None,
        metavar="S",
        help="simulated time (default: each experiment's own)",
    )
    p.add_argument(
        "--out",
        required=True,
        metavar="RUNS.csv|RUNS.parquet",
        help="the table of runs, one row per run (CSV or Parquet by the suffix)",
    )
    p.add_argument(
        "--png",
        default=None,
        metavar="FILE.png",
        help="summary figure (default: OUT with .png)",
    )
    cli_units.store_alias(p, "--figure", dest="png", default=None)  # the old spelling
    p.add_argument(
        "--workers", type=numbers.WORKERS, default=None, help="local processes (default: cores)"
    )
    p.add_argument(
        "--scheduler",
        default=None,
        metavar="ADDRESS",
        help="dask.distributed scheduler address (tcp://host:8786): run there instead",
    )
    p.add_argument(
        "--png-dir", metavar="DIR", help="write one figure per run into DIR (as simulate --png)"
    )
    p.add_argument(
        "--csv-dir", metavar="DIR", help="write one CSV per run into DIR (as simulate --csv)"
    )
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--fail-on-trip", action="store_true", help=FAIL_ON_TRIP_HELP)
    # the old spelling, kept working but no longer shown
    p.add_argument("--no-progress", action="store_true", dest="quiet", help=argparse.SUPPRESS)
    p.set_defaults(handler=_sweep)


def _sweep(args: argparse.Namespace) -> int:
    from fuzzkit.control.gains import read_gains
    from fuzzkit.studies.experiments import experiment
    from fuzzkit.studies.sweep import check_table_path, run_sweep, sweep_specs, write_table
    from fuzzkit.viz.sweep_figure import write_sweep_figure

    for name in args.experiments:
        exp = experiment(name)  # a bad name or scenario file fails here, before any run
        for latency in args.latency or ():
            cli_units.check_latency_fits(latency, exp, args.duration)
    names = list(args.experiments)  # what each run loads: a shipped name or the file
    controllers = [c.strip() for c in args.controller.split(",")]
    for c in controllers:
        if c not in RUN_CONTROLLERS:
            raise ConfigError(
                f"--controller: unknown {c!r} (expected {', '.join(RUN_CONTROLLERS)})"
            )
    out = check_table_path(args.out)
    figure = Path(args.png) if args.png else out.with_suffix(".png")
    from fuzzkit.fileio import check_output_path

    check_output_path(figure, "figure")
    from fuzzkit.viz.run_files import check_trace_dir

    png_dir = check_trace_dir(args.png_dir, "--png-dir")
    csv_dir = check_trace_dir(args.csv_dir, "--csv-dir")
    ks: list[float | None] = [None] if args.stiffness is None else list(args.stiffness)
    gains = None
    if args.gains:
        gains = {
            f: {c: read_gains(f, c.removeprefix("adaptive-"), required=False) for c in controllers}
            for f in args.gains.split(",")
        }
    specs = sweep_specs(
        names,
        controllers,
        stiffnesses_n_per_mm=ks,
        latencies=list(args.latency) if args.latency else [None],
        seeds=args.seeds,
        gains=gains,
        plant=args.plant,
        rulebase=args.rulebase,
        loop=args.loop or "auto",
        duration_s=args.duration,
        controller_specs=args.spec.split(",") if args.spec else (),
        controller_impl=args.controller_impl,
    )
    from fuzzkit.progress import progress_bar

    with progress_bar(len(specs), "sweep", quiet=args.quiet, unit="run") as bar:

        def progress(done: int) -> None:
            bar.update(done - bar.n)

        if png_dir is None and csv_dir is None:
            rows = run_sweep(
                specs, workers=args.workers, scheduler=args.scheduler, progress=progress
            )
        else:
            rows = run_sweep_traced(specs, png_dir, csv_dir, args.workers, args.scheduler, progress)
    write_table(rows, out)
    write_sweep_figure(rows, figure)
    where = args.scheduler or f"{args.workers or 'all'} local cores"
    print(f"{len(rows)} runs ({where}) -> {out}, {figure}")
    tripped = sum(bool(r.get("tripped")) for r in rows)
    if tripped:
        print(f"{tripped} of {len(rows)} runs tripped the safety limit")
    exceeded = sum(r.get("limit_exceeded_s") is not None for r in rows)
    if exceeded:
        print(f"{exceeded} of {len(rows)} runs' true force passed the safety limit")
    return EXIT_TRIPPED if args.fail_on_trip and (tripped or exceeded) else 0


def run_sweep_traced(
    specs: list[Any],
    png_dir: Path | None,
    csv_dir: Path | None,
    workers: int | None,
    scheduler: str | None,
    progress: Any,
) -> list[dict[str, Any]]:
    """:func:`fuzzkit.studies.sweep.run_sweep`, also writing each run's figure and CSV as
    ``run<index>.png``/``.csv`` (the index is the row's ``run`` column); the workers render them,
    this process writes them (atomically)."""
    from fuzzkit.studies.batch import map_runs
    from fuzzkit.viz.run_files import execute_traced, write_traces

    for s in specs:
        s.resolved_loop()
    items = [(s, png_dir is not None, csv_dir is not None) for s in specs]
    done = map_runs(execute_traced, items, workers=workers, scheduler=scheduler, progress=progress)
    rows = []
    width = len(str(len(done) - 1))
    for index, (row, files) in enumerate(done):
        stem = f"run{index:0{width}d}"
        write_traces(
            files,
            png_dir / f"{stem}.png" if png_dir else None,
            csv_dir / f"{stem}.csv" if csv_dir else None,
        )
        rows.append({"run": stem, **row})
    return rows
