"""``fuzzkit simulate`` and ``fuzzkit compare``: the paper's experiments in closed loop."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from fuzzkit.cli import (
    EXIT_TRIPPED,
    RULEBASE_SPEC_HELP,
    add_controller_impl_argument,
    add_plant_argument,
    add_quiet_argument,
    numbers,
)
from fuzzkit.cli import units as cli_units
from fuzzkit.control.names import KINDS as CONTROLLERS
from fuzzkit.control.names import RUN_CONTROLLERS
from fuzzkit.errors import ConfigError
from fuzzkit.fileio import check_output_path
from fuzzkit.studies.outcome import limit_text, settling_text
from fuzzkit.units import latency_text

FAULT_KINDS = ("none", "spike", "nan", "dropout", "delay")  # fuzzkit.loop.faults.FAULTS


FAIL_ON_TRIP_HELP = (
    f"exit with status {EXIT_TRIPPED} when a run tripped the safety limit or its true force "
    "passed it untripped (after printing and writing everything; 0 otherwise, 2 for bad input)"
)

#: ``fuzzkit compare --protocol`` choices (fuzzkit.studies.protocol.PROTOCOLS).
PROTOCOL_CHOICES = ("matched", "tuned", "default")


def register(subparsers: Any) -> None:
    """Add the ``simulate`` and ``compare`` subcommands."""
    sim = subparsers.add_parser(
        "simulate",
        help="run one experiment (E1, E2, E3) in closed loop and print its metrics",
        description="Run one of the paper's experiments with a PI or fuzzy-PI force loop.",
        epilog="examples:\n"
        "  fuzzkit simulate E1\n"
        "  fuzzkit simulate E3 --controller pi --plant arm6 --rrd e3_pi.rrd\n"
        "  rerun e3_pi.rrd     (open the recording in the Rerun viewer)\n"
        "  fuzzkit simulate E2 --gains gains.yaml --json",
    )
    sim.add_argument(
        "experiment",
        metavar="EXPERIMENT",
        help="E1, E2, E3 (shipped scenarios) or a scenario file TASK.yaml",
    )
    sim.add_argument(
        "--controller",
        choices=RUN_CONTROLLERS,
        default="fuzzy-pi",
        help="force controller (adaptive-*: the shipped gains under the kit's stiffness schedule)",
    )
    sim.add_argument(
        "--rulebase",
        default="macvicar_whelan",
        metavar="RB",
        help="rule base for fuzzy-pi: " + RULEBASE_SPEC_HELP,
    )
    add_plant_argument(sim, "simulated robot")
    sim.add_argument(
        "--seed", type=numbers.SEED, default=0, help="seed of the sensor noise and of the faults"
    )
    sim.add_argument(
        "--stiffness",
        type=cli_units.stiffness,
        metavar=cli_units.STIFFNESS_METAVAR,
        help=f"contact stiffness of the environment ({cli_units.STIFFNESS_HELP}; default: the "
        "scenario's)",
    )
    sim.add_argument(
        "--latency",
        type=cli_units.latency_or_sensor,
        metavar=cli_units.LATENCY_METAVAR,
        help=f"{cli_units.LATENCY_HELP} (default: the scenario's; one number sets the sensor "
        "delay only)",
    )
    sim.add_argument(
        "--fault",
        choices=FAULT_KINDS,
        help="inject a sensor fault at the strength the test suite uses (default: the "
        "scenario's, none for E1-E3)",
    )
    sim.add_argument(
        "--loop",
        choices=("compiled", "python"),
        default=None,
        help="compiled (the whole run as one numba function, arm6 and planar) or python (the "
        "loop plant by plant in Python); either runs the controller --controller-impl names. "
        "Default: compiled where the plant has it and the controller is the generated C, "
        "python otherwise",
    )
    sim.add_argument(
        "--fuzzy-impl",
        choices=("auto", "exact", "table", "c"),
        default="auto",
        help="with --controller-impl reference only: the reference controller's fuzzy-pi "
        "surface, exact (the exact engine), table (the rule base's double lookup table) or c "
        "(the rule base's generated C surface through ctypes; needs a C compiler). Default "
        "auto: the spec's surface (exact, or the table a spec's surface: names)",
    )
    add_controller_impl_argument(sim)
    sim.add_argument("--rrd", metavar="OUT.rrd", help="write a Rerun recording of the run")
    sim.add_argument(
        "--png",
        metavar="RUN.png",
        help="write a figure of the run: forces against set points per axis, error, correction "
        "(units on every axis; engagement and a trip marked)",
    )
    sim.add_argument(
        "--csv",
        metavar="RUN.csv",
        help="write the run as CSV, one row per period: t, measured and true forces, set points, "
        "e, de, du, u, status (columns: docs/simulation.md)",
    )
    sim.add_argument("--json", action="store_true", help="print the metrics as JSON")
    add_quiet_argument(sim, progress=False)
    sim.add_argument("--fail-on-trip", action="store_true", help=FAIL_ON_TRIP_HELP)
    sim.add_argument(
        "--gains",
        metavar="GAINS.yaml",
        help="gains file (fuzzkit.control.gains): flat {kp: .., ki: ..}, or keyed by controller "
        "as fuzzkit tune writes (default: the default gains)",
    )
    sim.add_argument(
        "--spec",
        metavar="SPEC.yaml",
        help="run the controller of a controller spec (docs/controller.md): its kind, rule "
        "base, gains, axes, set points, limits, safety and sensor front end replace "
        "--controller, --rulebase and the scenario's task (not with --gains)",
    )
    sim.set_defaults(handler=_simulate)

    cmp_ = subparsers.add_parser(
        "compare",
        help="run PI and fuzzy-PI on experiments and print a comparison table",
        description="Run PI and fuzzy-PI on each experiment (default: E1 E2 E3) and print "
        "one table of their metrics (contact, overshoot, settling, steady-state error, peak "
        "force) per force-controlled axis.",
        epilog="examples:\n"
        "  fuzzkit compare\n"
        "  fuzzkit compare E1 --plant arm6 --rrd-dir runs/\n"
        "  fuzzkit compare E2 E3 --gains gains.yaml --json",
    )
    cmp_.add_argument(
        "experiments",
        nargs="*",
        metavar="EXPERIMENT",
        default=["E1", "E2", "E3"],
        help="E1, E2, E3 (default: all three)",
    )
    cmp_.add_argument(
        "--rulebase",
        default="macvicar_whelan",
        metavar="RB",
        help="rule base for fuzzy-pi: " + RULEBASE_SPEC_HELP,
    )
    add_plant_argument(cmp_, "simulated robot")
    cmp_.add_argument("--seed", type=numbers.SEED, default=0, help="sensor-noise seed")
    cmp_.add_argument(
        "--latency",
        type=cli_units.latency_or_sensor,
        metavar=cli_units.LATENCY_METAVAR,
        help=f"{cli_units.LATENCY_HELP} (default: each scenario's; one number sets the sensor "
        "delay only)",
    )
    cmp_.add_argument(
        "--gains",
        metavar="GAINS.yaml",
        help="gains file (fuzzkit.control.gains), e.g. from fuzzkit tune (default: the "
        "protocol's gains)",
    )
    cmp_.add_argument(
        "--protocol",
        choices=PROTOCOL_CHOICES,
        default="matched",
        help="which gains each controller runs with: matched (default; fuzzy-PI gains derived "
        "from the PI's through the rule base's measured slope at the origin, so both have the "
        "same small-signal gain), tuned (both controllers' tuned gains from --gains), default "
        "(the hand-set defaults, --gains on top); see docs/simulation.md",
    )
    cmp_.add_argument("--json", action="store_true", help="print every run's metrics as JSON")
    add_quiet_argument(cmp_, progress=False)
    cmp_.add_argument("--fail-on-trip", action="store_true", help=FAIL_ON_TRIP_HELP)
    cmp_.add_argument("--rrd-dir", metavar="DIR", help="write one .rrd per run into DIR")
    cmp_.add_argument(
        "--png-dir", metavar="DIR", help="write one figure per run into DIR (as simulate --png)"
    )
    cmp_.add_argument(
        "--csv-dir", metavar="DIR", help="write one CSV per run into DIR (as simulate --csv)"
    )
    cmp_.set_defaults(handler=_compare)

    scn = subparsers.add_parser(
        "scenario",
        help="print a shipped scenario file (E1, E2, E3, regulate) to start your own from",
        description="Print the YAML of a shipped scenario, to copy and edit; the copy runs "
        "with simulate, compare, sweep and tune as the shipped one does. Without a name, list "
        "the shipped scenarios.",
        epilog="examples:\n"
        "  fuzzkit scenario E1 > my_task.yaml\n"
        "  fuzzkit validate my_task.yaml\n"
        "  fuzzkit simulate ./my_task.yaml",
    )
    scn.add_argument(
        "name",
        nargs="?",
        metavar="NAME",
        help="E1, E2, E3, or regulate (the task fuzzkit stability certifies)",
    )
    scn.set_defaults(handler=_scenario)


def load_gains(path: str | None, controller: str, required: bool = True) -> dict[str, float]:
    """Gain overrides for ``controller`` from a gains file (see
    ``fuzzkit.control.gains.read_gains``)."""
    from fuzzkit.control.gains import read_gains

    return read_gains(path, controller, required)


def _surface_for(controller: str, rulebase: str) -> Any:
    if controller != "fuzzy-pi":
        return None
    from fuzzkit.loop.python_loop import load_surface

    return load_surface(rulebase)


def _fmt(v: Any, digits: int = 2) -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.{digits}f}"
    return str(v)


def _simulate(args: argparse.Namespace) -> int:
    from fuzzkit.studies.experiments import experiment
    from fuzzkit.studies.metrics import summary

    exp = experiment(args.experiment)  # reject a bad name before loading anything
    if args.rrd:
        check_output_path(args.rrd, ".rrd file")
    from fuzzkit.viz.run_files import check_trace_path, write_run_traces

    png = check_trace_path(args.png, "--png", ".png") if args.png else None
    csv = check_trace_path(args.csv, "--csv", ".csv") if args.csv else None
    from fuzzkit.loop.spec import RunSpec
    from fuzzkit.studies.batch import gains_items, resolve, run_spec

    latency = None
    if args.latency is not None:
        sensor, command = args.latency
        latency = (sensor, exp.latency_periods[1] if command is None else command)
    cli_units.check_latency_fits(latency, exp)
    if args.spec and args.gains:
        raise ConfigError("--spec: a controller spec holds its gains; give --spec or --gains")
    spec = RunSpec(
        experiment=args.experiment,
        controller=args.controller,
        plant=args.plant,
        stiffness_n_per_mm=args.stiffness,
        latency=latency,
        seed=args.seed,
        gains=gains_items(load_gains(args.gains, args.controller.removeprefix("adaptive-"))),
        gains_label=args.gains or "default",
        rulebase=args.rulebase,
        loop=args.loop or "auto",
        fuzzy_impl=args.fuzzy_impl,
        fault=args.fault,
        controller_spec=args.spec,
        controller_impl=args.controller_impl,
    )
    result = run_spec(spec)
    ran, ran_exp, plant = resolve(spec)  # with a controller spec, its controller and rule base
    gains, source = ran_gains(ran, ran_exp, args.gains)
    if args.rrd:
        from fuzzkit.viz.traces import write_run_rrd

        # plant: the 3-D E3's floor and wall, for the drawing
        write_run_rrd(
            result,
            args.rrd,
            None if isinstance(plant, str) else plant,
            _fuzzy(ran, ran_exp, gains),
        )
    named = ran_names(ran, ran_exp, source)
    written = write_run_traces(result, png, csv, ran_text(named))
    data = summary(result)
    data["gains"] = gains
    data.update(named)
    _warn_impact(ran_exp, sum(data["latency_periods"]))
    exceeded = data["limit_exceeded"]
    status = EXIT_TRIPPED if args.fail_on_trip and (result.tripped or exceeded) else 0
    if args.json:
        print(json.dumps(data, indent=2, allow_nan=False))  # never invalid JSON
        return status
    print(
        f"{data['experiment']} {data['controller']} on {data['plant']}: "
        f"{data['sim_time_s']:.2f} s simulated in {data['wall_time_s']:.2f} s "
        f"({data['loop']} loop, {data['real_time_factor']}x real time in CPU time; "
        f"controller: {data['controller_impl']})"
    )
    print(f"  ran: {ran_text(named)}")
    print(f"  {task_text(result.experiment)}")
    print(f"  gains: {_gains_text(gains)} ({source})")
    print(
        f"  stiffness {data['stiffness']:g} N/mm, latency {latency_text(data['latency_periods'])} "
        f"periods (sensor:command), fault {data['fault']}, seed {data['seed']}, "
        f"safety limit {data['safety_limit']:g} N"
    )
    tripped = bool(data["tripped"])
    for name, m in data["axes"].items():
        print(
            f"  {name}: set {m['setpoint']:g} N, first contact {_fmt(m['first_contact_s'])} s, "
            f"overshoot {_fmt(m['overshoot_pct'], 1)} %, settling {settling_text(m, tripped)}, "
            f"steady error {_fmt(m['steady_state_error_mean'])} +- "
            f"{_fmt(m['steady_state_error_std'])} N, RMS moving {_fmt(m['rms_error'])} N, "
            f"peak {_fmt(m['peak_force_true'], 1)} N true ({_fmt(m['peak_force_measured'], 1)} N "
            f"measured), contact lost {_fmt(m['contact_lost_s'])} s"
        )
    if exceeded is not None:
        print(f"  SAFETY: {limit_text(exceeded, data['safety_limit'], result.tripped)}")
    if result.faults or result.tripped:
        print(f"  sensor faults: {result.faults}, safety trip: {result.tripped}")
    for msg, count in sorted(result.messages.items()):
        print(f"  plant: {msg} ({count} periods)")
    for path in [*([args.rrd] if args.rrd else []), *written]:
        print(f"  wrote {path}")
    return status


def ran_names(ran: Any, exp: Any, gains_source: str) -> dict[str, str | None]:
    """What ran, as the JSON of ``simulate`` and ``compare`` names it: ``controller_spec`` (its
    name, or None), ``rulebase`` (fuzzy-PI's, or None) and ``gains_source``; the
    implementation is the result's ``controller_impl``."""
    cs = exp.controller_spec
    return {
        "controller_spec": None if cs is None else cs.name,
        "rulebase": ran.rulebase if ran.controller == "fuzzy-pi" else None,
        "gains_source": gains_source,
    }


def ran_text(named: dict[str, str | None]) -> str:
    """:func:`ran_names` in words: ``controller spec e1_fuzzy, rule base macvicar_whelan;
    gains: controller spec e1_fuzzy``."""
    parts = [
        f"{what} {named[key]}"
        for key, what in (("controller_spec", "controller spec"), ("rulebase", "rule base"))
        if named[key] is not None
    ]
    return f"{', '.join(parts) or 'pi'}; gains: {named['gains_source']}"


def task_text(exp: Any) -> str:
    """What ran: the scenario's world (its title up to the colon) and the force-controlled
    axes with their set points as the run had them (a controller spec's, when one ran; not
    the scenario title's)."""
    world = exp.title.partition(":")[0].strip() or exp.name
    axes = ", ".join(
        f"{exp.setpoints[i]:g} N along {'xyz'[i]}" for i in (2, 0, 1) if exp.selection[i]
    )
    spec = exp.controller_spec
    source = f" (controller spec {spec.name})" if spec is not None else ""
    return f"{world}: {axes}{source}"


def _warn_impact(exp: Any, latency_periods: int) -> None:
    """Say on stderr when the run's path approaches contact faster than the spec's impact
    speed (:mod:`fuzzkit.control.impact`)."""
    from fuzzkit.control.impact import impact_warning, path_approach_speed

    cs = exp.controller_spec
    if cs is None:
        return
    speed = path_approach_speed(exp.scenario.path, cs.selection)
    msg = impact_warning(cs, speed, latency_periods, f"{exp.name}'s path")
    if msg is not None:
        print(f"warning: {msg}", file=sys.stderr)


def ran_gains(ran: Any, exp: Any, gains_file: str | None) -> tuple[dict[str, Any], str]:
    """The complete gains a run used and where they came from: a controller spec's per axis
    (``{axis: {kp: ..}}``), or the defaults with the gains file's values on top (as the runner
    builds its controller)."""
    from fuzzkit.studies.experiments import DEFAULT_GAINS

    cs = exp.controller_spec
    if cs is not None:
        per_axis = {
            a.axis: {k: v for k, v in (("kp", a.kp), ("ki", a.ki), ("kx", a.kx)) if v is not None}
            for a in cs.axes
        }
        return per_axis, f"controller spec {cs.name}"
    source = f"{gains_file} over the defaults" if gains_file else "the defaults"
    return {**DEFAULT_GAINS[ran.controller], **dict(ran.gains)}, source


def _gains_text(gains: dict[str, Any]) -> str:
    if all(isinstance(v, dict) for v in gains.values()):
        return "; ".join(f"{axis}: {_gains_text(g)}" for axis, g in gains.items())
    return ", ".join(f"{k}={v:.6g}" for k, v in gains.items())


def _fuzzy(ran: Any, exp: Any, gains: dict[str, Any]) -> Any:
    """The rule base (its inputs in role order: a controller spec's ``inputs:`` applied) and
    gains of a fuzzy-PI run, for its recording's rule activity."""
    if ran.controller != "fuzzy-pi":
        return None
    cs = exp.controller_spec
    if cs is not None and cs.rulebase is not None:
        from fuzzkit.control.spec import role_ordered

        return role_ordered(cs, cs.rulebase), gains
    from fuzzkit.control.loop_rulebase import load_loop_rulebase

    return load_loop_rulebase(ran.rulebase), gains


def comparison_table(rows: list[dict[str, Any]]) -> str:
    """Format PI vs fuzzy-PI summaries (``fuzzkit.studies.experiments.summary``) as a text table."""
    # the experiment column is as wide as its longest name (a scenario file's name can be long)
    w = max([3, *(len(str(d["experiment"])) for d in rows)]) + 1
    head = (
        f"{'exp':<{w}}{'axis':<5}{'set N':>6}  {'controller':<9}{'contact s':>10}"
        f"{'overshoot %':>12}"
        f"{'settle s':>14}"
        f"{'ss mean N':>11}{'ss std N':>10}{'rms move N':>12}{'peak N':>8}{'lost s':>8}"
    )
    lines = [head, "-" * len(head)]
    for data in rows:
        for axis, m in data["axes"].items():
            lines.append(
                f"{data['experiment']:<{w}}{axis:<5}{m['setpoint']:>6g}  {data['controller']:<9}"
                f"{_fmt(m.get('first_contact_s')):>10}{_fmt(m['overshoot_pct'], 1):>12}"
                f"{settling_text(m, bool(data.get('tripped'))).removesuffix(' s'):>14}"
                f"{_fmt(m['steady_state_error_mean']):>11}{_fmt(m['steady_state_error_std']):>10}"
                f"{_fmt(m['rms_error']):>12}{_fmt(m['peak_force'], 1):>8}"
                f"{_fmt(m['contact_lost_s']):>8}"
            )
    return "\n".join(lines)


def compare_spec(name: str, controller: str, gains: dict[str, float], args: Any) -> Any:
    """The run ``fuzzkit compare`` makes of one experiment and controller: the same
    :class:`~fuzzkit.studies.batch.RunSpec` as ``fuzzkit simulate`` and ``fuzzkit report``
    (compiled loop where the plant has one), so that one experiment gives one number."""
    from fuzzkit.loop.spec import RunSpec
    from fuzzkit.studies.batch import gains_items
    from fuzzkit.studies.experiments import experiment

    latency = None
    if args.latency is not None:  # one number sets the sensor delay only, as simulate
        sensor, command = args.latency
        exp = experiment(name)
        latency = (sensor, exp.latency_periods[1] if command is None else command)
        cli_units.check_latency_fits(latency, exp)
    return RunSpec(
        experiment=name,
        controller=controller,
        plant=args.plant,
        latency=latency,
        seed=args.seed,
        gains=gains_items(gains),
        gains_label=args.protocol,
        rulebase=args.rulebase,
    )


def _compare(args: argparse.Namespace) -> int:
    from fuzzkit.studies.batch import experiment_and_plant, resolve, run_spec
    from fuzzkit.studies.experiments import experiment
    from fuzzkit.studies.metrics import summary

    for name in args.experiments:
        experiment(name)  # reject unknown names before any simulation runs
        compare_spec(name, "pi", {}, args)  # and a latency longer than the run
    if args.rrd_dir and not Path(args.rrd_dir).is_dir():
        raise ConfigError(f"{args.rrd_dir}: folder does not exist")
    from fuzzkit.viz.run_files import check_trace_dir, write_run_traces

    png_dir = check_trace_dir(args.png_dir, "--png-dir")
    csv_dir = check_trace_dir(args.csv_dir, "--csv-dir")
    from fuzzkit.control.loop_rulebase import load_loop_rulebase
    from fuzzkit.studies.protocol import format_gains, protocol_gains

    surface = _surface_for("fuzzy-pi", args.rulebase)
    chosen = protocol_gains(args.protocol, surface, args.gains)
    if args.gains:
        for controller in CONTROLLERS:
            has = bool(load_gains(args.gains, controller, required=False))
            if not has and not (controller == "fuzzy-pi" and args.protocol == "matched"):
                print(
                    f"note: {args.gains} has no gains for {controller}: it runs on the defaults",
                    file=sys.stderr,
                )
            if has and controller == "fuzzy-pi" and args.protocol == "matched":
                print(
                    f"note: --protocol matched uses only ki and the limits of {args.gains}'s "
                    "fuzzy-pi gains; kp and kx are matched to the PI (--protocol default or "
                    "tuned runs them as they are)",
                    file=sys.stderr,
                )
    rows = []
    for name in args.experiments:
        for controller in CONTROLLERS:
            spec = compare_spec(name, controller, chosen[controller].gains, args)
            result = run_spec(spec)
            stem = f"{Path(name).stem.upper()}_{controller}"  # E1_pi, MY_TASK_fuzzy-pi
            if args.rrd_dir:
                from fuzzkit.viz.traces import write_run_rrd

                drawn = experiment_and_plant(spec)[1]  # E3 on arm6: its floor and wall
                write_run_rrd(
                    result,
                    Path(args.rrd_dir) / f"{stem}.rrd",
                    None if isinstance(drawn, str) else drawn,
                    (load_loop_rulebase(args.rulebase), chosen[controller].gains),
                )
            ran, ran_exp, _ = resolve(spec)
            named = ran_names(ran, ran_exp, chosen[controller].source)
            write_run_traces(
                result,
                png_dir / f"{stem}.png" if png_dir else None,
                csv_dir / f"{stem}.csv" if csv_dir else None,
                ran_text(named),
            )
            row = summary(result)
            row["protocol"] = args.protocol
            row["gains"] = dict(chosen[controller].gains)
            row.update(named)
            rows.append(row)
    if args.json:
        print(json.dumps(rows, indent=2, allow_nan=False))
    else:
        print(f"protocol: {args.protocol} (rule base {args.rulebase})")
        for controller in CONTROLLERS:
            print(f"  {format_gains(chosen[controller])}")
        print(comparison_table(rows))
    failed = any(r["tripped"] or r["limit_exceeded"] for r in rows)
    return EXIT_TRIPPED if args.fail_on_trip and failed else 0


def _scenario(args: argparse.Namespace) -> int:
    from fuzzkit.studies.experiments import SHIPPED_SCENARIOS, experiment, shipped_name
    from fuzzkit.studies.scenario_file import shipped_scenario_text

    if args.name is None:
        for name in SHIPPED_SCENARIOS:
            print(f"{name}  {experiment(name).title}")
        return 0
    shipped = shipped_name(args.name)
    if shipped is None:
        raise ConfigError(
            f"no shipped scenario {args.name!r} (expected one of {', '.join(SHIPPED_SCENARIOS)})"
        )
    sys.stdout.write(shipped_scenario_text(shipped))
    return 0
