"""``fuzzkit tune`` (optimal gains to a gains file) and ``fuzzkit report`` (PI vs fuzzy-PI)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from fuzzkit.cli import (
    EXIT_INTERRUPTED,
    RULEBASE_SPEC_HELP,
    add_controller_impl_argument,
    add_plant_argument,
    numbers,
)
from fuzzkit.cli import units as cli_units
from fuzzkit.control.names import RUN_CONTROLLERS
from fuzzkit.errors import ConfigError
from fuzzkit.fileio import check_output_path
from fuzzkit.studies.outcome import settling_text
from fuzzkit.units import latencies_text


def register(subparsers: Any) -> None:
    """Add the ``tune`` and ``report`` subcommands."""
    tune = subparsers.add_parser(
        "tune",
        help="find optimal gains (Kp, Ki, Kx) by simulation and write a gains file",
        description=(
            "Minimise the closed-loop cost (ITAE of the force error plus penalties for "
            "overshoot, force above the safety limit and contact loss; see fuzzkit.studies.tuning) "
            "over the experiments and stiffnesses given, by differential evolution and a "
            "local polish. Ctrl-C stops early and still writes the best gains so far "
            "(exit status 130)."
        ),
        epilog="examples:\n"
        "  fuzzkit tune E1 E2 E3 --controller fuzzy-pi --out gains.yaml\n"
        "  fuzzkit tune E2 --controller pi --stiffness 10 --budget 60 --out gains.yaml\n"
        "  fuzzkit tune E1 E2 E3 --plant arm6 --stiffness 5,10,20 --latency 0:0,1:1,3:3 "
        "--out gains.yaml\n"
        "  fuzzkit simulate E2 --gains gains.yaml      (use the tuned gains)",
    )
    tune.add_argument("experiments", nargs="+", metavar="EXPERIMENT", help="E1, E2, E3")
    tune.add_argument(
        "--controller",
        choices=RUN_CONTROLLERS,
        default="fuzzy-pi",
        help="controller to tune (adaptive-*: the base gains under the kit's stiffness schedule)",
    )
    tune.add_argument(
        "--rulebase",
        default="macvicar_whelan",
        metavar="RB",
        help="rule base for fuzzy-pi: " + RULEBASE_SPEC_HELP,
    )
    add_plant_argument(tune, "simulated robot to tune on")
    tune.add_argument(
        "--stiffness",
        type=cli_units.stiffnesses,
        default="5,10,20",
        metavar=cli_units.STIFFNESSES_METAVAR,
        help=f"environment stiffnesses to tune over at once ({cli_units.STIFFNESS_HELP}; "
        "default 5,10,20)",
    )
    tune.add_argument(
        "--budget", type=numbers.BUDGET, default=120, help="most gain sets simulated (default 120)"
    )
    tune.add_argument("--seed", type=numbers.SEED, default=0, help="optimiser seed (default 0)")
    tune.add_argument(
        "--workers",
        type=numbers.WORKERS,
        default=None,
        help="worker processes (default: every core)",
    )
    tune.add_argument(
        "--latency",
        type=cli_units.latencies,
        default=None,
        metavar=cli_units.LATENCIES_METAVAR,
        help=f"{cli_units.LATENCY_HELP}, to tune over at once (default: each experiment's own)",
    )
    tune.add_argument(
        "--loop",
        choices=("compiled", "python"),
        default=None,
        help="default: the compiled loop where the plant has one (arm6, planar) and the "
        "controller is the generated C (--controller-impl auto or c)",
    )
    add_controller_impl_argument(tune)
    tune.add_argument(
        "--scheduler",
        default=None,
        metavar="ADDRESS",
        help="dask.distributed scheduler (tcp://host:8786): price the candidates on its workers",
    )
    tune.add_argument("--out", required=True, metavar="GAINS.yaml", help="gains file to write")
    tune.add_argument(
        "--spec",
        metavar="SPEC.yaml",
        help="tune the gains of a controller spec (docs/controller.md): every run is the spec's "
        "controller (its kind, rule base, task, limits, safety and front end) with the "
        "candidate kp, ki, kx on every axis; replaces --controller and --rulebase",
    )
    tune.add_argument(
        "--spec-out",
        metavar="SPEC.yaml",
        help="also write a controller spec: --spec's with the tuned gains, or else the first "
        "experiment's task (axes, set points, safety) with the tuned gains on every axis and "
        "no sensor front end",
    )
    tune.add_argument(
        "--replace",
        action="store_true",
        help="overwrite --out (default: keep the other controller's entry if the file has one)",
    )
    tune.add_argument(
        "--admit",
        choices=("case", "experiment"),
        default="case",
        help="which gain sets may be saved: case (default) = no worse than the default gains "
        "on every experiment x stiffness case; experiment = no worse on each experiment's "
        "mean over the stiffnesses (a compromise: may be worse at some stiffness)",
    )
    tune.add_argument(
        "--certify",
        type=cli_units.stiffnesses,
        default=None,
        metavar=cli_units.STIFFNESSES_METAVAR,
        help="search only gains certified stable (fuzzkit stability, docs/stability.md) at "
        f"each of these contact stiffnesses ({cli_units.STIFFNESS_HELP}), at every "
        "--certify-latency (default: no certification)",
    )
    tune.add_argument(
        "--certify-latency",
        type=cli_units.latencies,
        default="0:0,1:1",
        metavar=cli_units.LATENCIES_METAVAR,
        help=f"with --certify: the {cli_units.LATENCY_HELP} to certify at",
    )
    tune.add_argument(
        "--force",
        action="store_true",
        help="write --out even when the result is worse than the starting gains on the robust "
        "cost (without it, such a result is reported and not written, exit status 1)",
    )
    tune.add_argument("--quiet", action="store_true", help="no progress bar")
    tune.set_defaults(handler=_tune)

    rep = subparsers.add_parser(
        "report",
        help="run E1-E3 x {PI, fuzzy-PI} x {default, matched, tuned gains} and judge the "
        "paper's claims per setting; write report.md + figures",
        description=(
            "Write DIR/report.md with force plots, the control surface, the stiffness study, "
            "the latency map, the comparison table and the paper's claims judged per setting "
            "(default, matched, tuned gains; matched and tuned at every latency and stiffness "
            "of the sweeps), plus one .rrd per run. Tunes both controllers on the same problem "
            "(E1-E3 on the report's plant, planar for --plant both, 5/10/20 N/mm x latency "
            "0+0, 1+1, 3+3) unless --gains-dir holds "
            "pi.yaml and fuzzy-pi.yaml. The folder appears complete or not at all: "
            "Ctrl-C stops with exit status 130 and leaves no partial report."
        ),
        epilog="examples:\n"
        "  fuzzkit report --out report\n"
        "  fuzzkit report --out report --plant both --budget 80 --workers 2\n"
        "  fuzzkit report --out report --gains-dir tuned/ --no-rrd\n"
        "  fuzzkit report --out /tmp/smoke --quick --budget 10 --no-rrd",
    )
    rep.add_argument(
        "--out", required=True, metavar="DIR", help="output folder (its parent must exist)"
    )
    add_plant_argument(rep, "plant(s) to run E1-E3 on", both=True)
    rep.add_argument(
        "--budget",
        type=numbers.BUDGET,
        default=40,
        help="tuning budget per controller (default 40)",
    )
    rep.add_argument("--gains-dir", metavar="DIR", help="folder with pi.yaml and fuzzy-pi.yaml")
    rep.add_argument(
        "--rulebase",
        default="macvicar_whelan",
        metavar="RB",
        help="rule base for fuzzy-pi: " + RULEBASE_SPEC_HELP,
    )
    rep.add_argument("--seed", type=numbers.SEED, default=0, help="optimiser seed")
    rep.add_argument(
        "--workers",
        type=numbers.WORKERS,
        default=None,
        help="tuning worker processes (default: every core)",
    )
    rep.add_argument("--no-rrd", action="store_true", help="skip the .rrd recordings")
    rep.add_argument(
        "--quick",
        action="store_true",
        help="small report for a smoke test: shorter tuning, stiffness and latency sweeps "
        "(fuzzkit.report.build.quick_options)",
    )
    rep.add_argument(
        "--spec",
        default=None,
        metavar="SPEC[,SPEC...]",
        help="controller specs (docs/controller.md) to run on E1-E3 as they ship, in a "
        "section of their own",
    )
    rep.add_argument("--quiet", action="store_true", help="no progress bars")
    rep.set_defaults(handler=_report)


def _tune(args: argparse.Namespace) -> int:
    from fuzzkit.control.gains import read_gains_file, write_gains
    from fuzzkit.progress import progress_bar
    from fuzzkit.studies.tuning import progress_callback, tune
    from fuzzkit.studies.tuning_check import compare_cases

    ks = tuple(args.stiffness)
    latencies = args.latency or None
    experiments, controller, rulebase, loop = _tuning_target(args)
    from fuzzkit.studies.experiments import experiment

    for e in experiments:
        for latency in latencies or ():
            cli_units.check_latency_fits(latency, experiment(e) if isinstance(e, str) else e)
    spec = None
    if args.spec:
        from fuzzkit.control.spec_reader import load_spec

        spec = load_spec(args.spec)
    constraint = (
        _certified_over(args, experiments[0], controller, rulebase, spec) if args.certify else None
    )
    out = Path(args.out)
    check_output_path(out, "gains file")
    if args.spec_out:
        check_output_path(args.spec_out, "controller spec")
    if out.is_file() and not args.replace:
        read_gains_file(out)  # an unreadable existing file is reported now, not after tuning
    start, start_name = _starting_gains(args, controller)
    with progress_bar(args.budget, f"tune {controller}", quiet=args.quiet, unit="gain set") as bar:
        result = tune(
            experiments,
            controller,
            rulebase,
            args.plant,
            ks,
            budget=args.budget,
            seed=args.seed,
            workers=args.workers,
            callback=progress_callback(bar),
            admit=args.admit,
            latencies=latencies,
            loop=loop,
            scheduler=args.scheduler,
            controller_impl=args.controller_impl,
            constraint=constraint,
            baseline=start,
        )
    if constraint is not None:
        where = (
            f"{'/'.join(f'{k:g}' for k in constraint.stiffnesses_n_per_mm)} N/mm x latency "
            f"{_latencies(constraint.latencies)} periods ({constraint.plant})"
        )
        if not constraint(result.gains):
            print(
                f"fuzzkit: no certified gains: no candidate certified at {where} beat "
                f"{start_name}, and {start_name} are not certified there; {out} not written",
                file=sys.stderr,
            )
            return 1
        print(f"certified stable at {where}: only certified gains were searched")
    print(
        f"tuned {result.controller} on {' '.join(result.experiments)} ({result.plant}, "
        f"{'/'.join(f'{k:g}' for k in ks)} N/mm"
        + (f", latency {_latencies(latencies)} periods" if latencies else "")
        + f"): {result.evaluations} evaluations in "
        f"{result.wall_time_s:.1f} s"
        + (" (interrupted: best so far)" if result.interrupted else "")
    )
    print(f"controller: {result.controller_impl}")
    # the full per-case runs (what the trip warning counts): not after Ctrl-C (the user wants
    # out)
    cases = [] if result.interrupted else compare_cases(result, seed=0)
    for line in tune_report_lines(result, cases, start_name, tuned_gains(result, spec)):
        print(line)
    warnings = honesty_warnings(result, cases, start_name)
    for line in warnings:
        print(line, file=sys.stderr)
    if is_worse(result) and not args.force:
        print(
            f"fuzzkit: {out} not written: the result is worse than {start_name} on the robust "
            "cost (--force writes it anyway)",
            file=sys.stderr,
        )
        return 1
    import dataclasses

    entry = dataclasses.replace(result.to_entry(), gains=tuned_gains(result, spec))
    _, kept = write_gains(out, entry, merge=not args.replace)
    print(f"wrote {out}" + (f" (kept the {', '.join(kept)} entry)" if kept else ""))
    if args.spec_out:
        _write_spec(args, result, entry.gains)
        print(f"wrote {args.spec_out}")
    if result.interrupted:
        print(f"fuzzkit: interrupted (Ctrl-C); {out} holds the best gains so far", file=sys.stderr)
        return EXIT_INTERRUPTED
    return 0


#: A result less than this much cheaper (% of the starting gains' robust cost) is reported
#: as "not better": the search changed nothing worth a new gains file.
NOT_BETTER_PCT = 1.0


def is_worse(result: Any) -> bool:
    """True when the result costs more than the starting gains on the robust cost."""
    return bool(result.cost > result.baseline_cost + 1e-12)


def honesty_warnings(result: Any, cases: Any, start: str) -> list[str]:
    """What ``tune`` warns about after the search (each line starts ``warning:``): the share
    of the robust grid's cases in which the tuned gains trip the safety limit, and a result
    that is not better (less than :data:`NOT_BETTER_PCT` % cheaper) or worse than ``start``
    (the gains the search started from) on the robust cost.

    ``result``: a ``fuzzkit.studies.tuning.TuneResult``; ``cases``: its
    ``fuzzkit.studies.tuning_check.compare_cases`` (empty: no trip count).
    """
    out = []
    tripped = [c.label for c in cases if c.tuned_tripped]
    if tripped:
        start_tripped = sum(bool(c.default_tripped) for c in cases)
        out.append(
            f"warning: the tuned gains trip the safety limit in {len(tripped)} of {len(cases)} "
            f"cases of the robust grid ({100.0 * len(tripped) / len(cases):.0f} %): "
            f"{', '.join(tripped)}; {start} trip in {start_tripped}"
        )
    versus = (
        f"{result.cost:.6g} vs {result.baseline_cost:.6g}, "
        f"{_pct(result.cost, result.baseline_cost)}"
    )
    if is_worse(result):
        out.append(f"warning: the result is worse than {start} on the robust cost ({versus})")
    elif result.cost > result.baseline_cost * (1.0 - NOT_BETTER_PCT / 100.0):
        out.append(
            f"warning: the result is not better than {start} on the robust cost ({versus}; "
            f"less than {NOT_BETTER_PCT:g} % cheaper)"
        )
    return out


def _starting_gains(args: argparse.Namespace, controller: str) -> tuple[Any, str]:
    """The gains the search starts from and is judged against: a ``--spec``'s own (its lead
    axis's, :func:`fuzzkit.control.spec.lead_axis`, which the search moves with the other axes
    keeping their ratios), with its correction limit as ``u_min``/``u_max``; or None for the
    defaults; and how to name them. A spec whose axes differ is said so once, here."""
    if not args.spec:
        return None, "the default gains"
    from fuzzkit.control.spec import lead_axis
    from fuzzkit.control.spec_reader import load_spec
    from fuzzkit.studies.experiments import DEFAULT_GAINS

    spec = load_spec(args.spec)
    lead = lead_axis(spec)
    if len({(a.kp, a.ki, a.kx) for a in spec.axes}) != 1:
        others = ", ".join(a.axis for a in spec.axes if a is not lead)
        print(
            f"note: {args.spec}'s axes have different gains; tune searches axis {lead.axis}'s "
            f"(the largest set point) and scales {others} with them, keeping their ratios",
            file=sys.stderr,
        )
    gains = {"kp": lead.kp, "ki": lead.ki}
    if controller == "fuzzy-pi" and lead.kx is not None:
        gains["kx"] = lead.kx
    return {**DEFAULT_GAINS[controller], **gains, **_spec_limits(spec)}, f"the gains of {args.spec}"


def _spec_limits(spec: Any) -> dict[str, float]:
    """A spec's correction limit as a gains file spells it (``u_min``, ``u_max``)."""
    return {"u_min": -spec.limits.correction_m, "u_max": spec.limits.correction_m}


#: Tuned gains are written as the shortest decimal within this relative distance of the value
#: found: a gain the search moved through log10 and back carries about 1e-15 of rounding
#: (``0.00020000000000000004``); the search itself resolves 0.002 decades (0.5 %).
GAIN_DIGITS_REL = 1e-12


def shortest_gain(value: float) -> float:
    """``value`` as the shortest decimal within :data:`GAIN_DIGITS_REL` of it (``repr`` of the
    result prints that decimal): ``0.00020000000000000004`` -> ``0.0002``."""
    for digits in range(1, 18):
        short = float(f"{value:.{digits}g}")
        if abs(short - value) <= GAIN_DIGITS_REL * abs(value):
            return short
    return value


def tuned_gains(result: Any, spec: Any) -> dict[str, float]:
    """What ``tune`` writes: the result's gains, each as :func:`shortest_gain`, with a
    ``--spec``'s own correction limit as ``u_min``/``u_max`` (not the defaults')."""
    gains = {k: shortest_gain(v) for k, v in result.gains.items()}
    return {**gains, **(_spec_limits(spec) if spec is not None else {})}


def _shortest_axes(spec: Any) -> Any:
    """``spec`` with every axis's gains as :func:`shortest_gain` (the axes scaled with the lead
    carry the factor's rounding, as the lead's own would)."""
    import dataclasses

    def short(v: float | None) -> float | None:
        return None if v is None else shortest_gain(v)

    axes = tuple(
        dataclasses.replace(a, kp=short(a.kp), ki=short(a.ki), kx=short(a.kx)) for a in spec.axes
    )
    return dataclasses.replace(spec, axes=axes)


def _tuning_target(args: argparse.Namespace) -> tuple[list[Any], str, str, str]:
    """What ``tune`` tunes: ``(experiments, controller, rule base, loop)``; with ``--spec``,
    the experiments carry the spec and its kind and rule base are the controller's."""
    loop = args.loop or "auto"
    if not args.spec and args.controller.startswith("adaptive-"):
        from fuzzkit.studies.batch import adaptive_spec_for
        from fuzzkit.studies.experiments import experiment, with_spec

        exps = [experiment(e) for e in args.experiments]
        experiments = [
            with_spec(
                e, adaptive_spec_for(e, args.controller, args.rulebase, sum(e.latency_periods))
            )
            for e in exps
        ]
        return experiments, args.controller.removeprefix("adaptive-"), args.rulebase, loop
    if not args.spec:
        return list(args.experiments), args.controller, args.rulebase, loop
    from fuzzkit.control.spec_reader import load_spec
    from fuzzkit.studies.experiments import experiment, with_spec

    spec = load_spec(args.spec)
    if args.plant == "arm6" and any(e.upper() == "E3" for e in args.experiments):
        raise ConfigError(
            "tune --spec: E3 on arm6 (the paper's 3-D world) cannot carry a spec yet; "
            "tune on E1, E2 or the planar plant"
        )
    experiments = [with_spec(experiment(e), spec) for e in args.experiments]
    return experiments, spec.kind, spec.rulebase_source or args.rulebase, loop


def _write_spec(args: argparse.Namespace, result: Any, gains: dict[str, float]) -> None:
    """The tuned gains as a controller spec (atomically): ``--spec``'s, or one of the first
    experiment's task."""
    import re

    from fuzzkit.control.spec import require_valid, with_gains
    from fuzzkit.control.spec_reader import load_spec
    from fuzzkit.control.spec_writer import dump_spec
    from fuzzkit.fileio import write_atomic
    from fuzzkit.formats.registry import load
    from fuzzkit.loop.task import spec_for
    from fuzzkit.studies.experiments import experiment

    header = (
        f"# written by fuzzkit tune {' '.join(args.experiments)} ({result.plant}); "
        "format: docs/controller.md\n"
    )
    if args.spec:
        import dataclasses
        import os

        tuned = _shortest_axes(with_gains(load_spec(args.spec), gains))
        if tuned.rulebase_source is not None and Path(tuned.rulebase_source).exists():
            # a rule base file given relative to the input spec: relative to the new one
            out_dir = Path(args.spec_out).resolve().parent
            ref = os.path.relpath(Path(tuned.rulebase_source).resolve(), out_dir)
            tuned = dataclasses.replace(tuned, rulebase_ref=ref)
        write_atomic(Path(args.spec_out), dump_spec(tuned, header))
        return
    exp = experiment(args.experiments[0])
    name = re.sub(r"\W", "_", Path(args.spec_out).stem) or "tuned"
    if not re.match(r"[A-Za-z_]", name):
        name = "c_" + name
    fuzzy = result.controller == "fuzzy-pi"
    spec = spec_for(
        exp,
        result.controller,
        gains,
        name,
        load(args.rulebase) if fuzzy else None,
        args.rulebase if fuzzy else None,
    )
    require_valid(spec)
    write_atomic(Path(args.spec_out), dump_spec(spec, header))


def _certified_over(
    args: argparse.Namespace, first: Any, controller: str, rulebase: str, spec: Any = None
) -> Any:
    """The ``--certify`` predicate on the first tuned experiment (its period, contact damping
    and sensor): with ``--spec`` the spec as it ships with the candidate gains
    (``fuzzkit.analysis.spec_certificate.SpecCertifiedOver``), else the options' controller
    (``fuzzkit.analysis.region.CertifiedOver``)."""
    from fuzzkit.analysis.region import CertifiedOver
    from fuzzkit.analysis.spec_certificate import SpecCertifiedOver
    from fuzzkit.studies.experiments import experiment

    ks = args.certify
    exp = experiment(first) if isinstance(first, str) else first
    if spec is not None:
        return SpecCertifiedOver(exp, spec, args.plant, tuple(ks), tuple(args.certify_latency))
    return CertifiedOver(
        exp,
        controller,
        args.plant,
        tuple(ks),
        tuple(args.certify_latency),
        rulebase,
    )


def _latencies(pairs: Any) -> str:
    return latencies_text(pairs)


def _pct(new: float, old: float) -> str:
    return f"{100.0 * (new - old) / old:+.1f} %" if old > 0.0 else "n/a"


def _metric(v: Any, unit: str, digits: int, missing: str) -> str:
    return missing if v is None else f"{v:.{digits}f}{unit}"


def tune_report_lines(
    result: Any, cases: Any, start: str = "the default gains", gains: Any = None
) -> list[str]:
    """What ``fuzzkit tune`` prints after the search: the rule, the verdict, per-case numbers.

    ``result`` is a ``fuzzkit.studies.tuning.TuneResult``, ``cases`` the
    ``fuzzkit.studies.tuning_check.compare_cases`` of it, ``start`` what the search started
    from and is judged against (the default gains, or a spec's), ``gains`` the gains as
    written (:func:`tuned_gains`; default: the result's).
    """
    what = "experiment x stiffness x latency" if result.latencies else "experiment x stiffness"
    rule = (
        f"no worse than {start} on every case ({what})"
        if result.admit == "case"
        else f"no worse than {start} on each experiment's mean over the stiffnesses"
    )
    lines = [f"  admissible: {rule}"]
    lines.append(
        f"  cost {result.cost:.6g} vs {start} {result.baseline_cost:.6g} "
        f"({_pct(result.cost, result.baseline_cost)})"
    )
    refused = result.refusals()
    if result.kept_defaults and refused:
        lines.append(f"  kept {start}: every cheaper candidate was worse than them somewhere")
    elif result.kept_defaults:
        lines.append(
            f"  kept {start}: none of the {result.evaluations} gain sets tried was cheaper"
        )
    if refused:
        lines.append(
            f"  the cheapest candidate (cost {result.cheapest_cost:.6g}, "
            f"{_pct(result.cheapest_cost, result.baseline_cost)} vs {start}) was refused: "
            f"worse than {start} on "
            + ", ".join(f"{k} ({c:.4g} vs {b:.4g}, {_pct(c, b)})" for k, c, b in refused)
        )
    if cases:
        lines.append(f"  per case, tuning cost and the full run ({start} -> tuned gains):")
    for c in cases:
        parts = [f"cost {c.default_cost:.4g} -> {c.tuned_cost:.4g} ({c.cost_change_pct:+.1f} %)"]
        for axis, d in c.default_axes.items():
            t = c.tuned_axes[axis]
            parts.append(
                f"{axis}: settling {settling_text(d, c.default_tripped)} -> "
                f"{settling_text(t, c.tuned_tripped)}, overshoot "
                f"{_metric(d['overshoot_pct'], ' %', 1, 'n/a')} -> "
                f"{_metric(t['overshoot_pct'], ' %', 1, 'n/a')}"
            )
        if c.default_tripped or c.tuned_tripped:
            parts.append(f"safety trip {c.default_tripped} -> {c.tuned_tripped}")
        verdict = "worse" if c.tuned_cost > c.default_cost + 1e-12 else "no worse"
        lines.append(f"    {c.label} ({verdict}): " + "; ".join(parts))
    for name, cost in result.experiment_costs.items():
        lines.append(
            f"  {name}: {cost:.6g} ({start}: {result.baseline_experiment_costs[name]:.6g})"
        )
    shown = ", ".join(f"{k}={v!r}" for k, v in (gains or result.gains).items())
    lines.append(f"  gains: {shown}" + (f" ({start})" if result.kept_defaults else ""))
    return lines


def _report(args: argparse.Namespace) -> int:
    from fuzzkit.report.build import build_report, quick_options

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
        specs=[Path(p) for p in args.spec.split(",")] if args.spec else (),
        **(quick_options(plants[0]) if args.quick else {}),
    )
    print(f"wrote {path}")
    return 0
