"""``fuzzkit stability``: certify the force loop over a grid of contact stiffness x latency."""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from fuzzkit.cli import RULEBASE_SPEC_HELP, add_plant_argument, add_quiet_argument, numbers
from fuzzkit.cli import units as cli_units
from fuzzkit.control.names import KINDS as CONTROLLERS
from fuzzkit.fileio import check_output_path
from fuzzkit.units import latency_text


def register(subparsers: Any) -> None:
    """Add the ``stability`` subcommand."""
    p = subparsers.add_parser(
        "stability",
        help="certify the force loop's stability over contact stiffness x latency",
        description="Certify each cell of a contact stiffness x latency grid, or say it cannot: "
        "a common quadratic Lyapunov function of the loop's linear model (docs/stability.md), "
        "found by an LMI and verified in numpy.",
        epilog="examples:\n"
        "  fuzzkit stability regulate --controller pi --plant arm6 --stiffness 5,10,100 "
        "--latency 0:0,1:1,4:4\n"
        "  fuzzkit stability E1 --controller fuzzy-pi --gains gains.yaml --stiffness 10,20 "
        "--latency 1:1 --json\n"
        "  fuzzkit stability regulate --controller pi --stiffness 5,10,20,50,100 "
        "--latency 0:0,2:2 --png region.png --simulate",
    )
    p.add_argument(
        "scenario",
        metavar="SCENARIO",
        help="regulate (guarded approach onto a flat surface, then hold), E1, E2, E3, or a "
        "scenario file TASK.yaml: its period, contact damping, sensor and set points",
    )
    p.add_argument(
        "--spec",
        metavar="SPEC.yaml",
        help="certify this controller spec as it ships: its controller, the axis's gains and "
        "set point, its low-pass, limits and surface method (not with --controller, --gains, "
        "--rulebase)",
    )
    p.add_argument(
        "--axis",
        choices=("x", "y", "z"),
        help="with --spec: the spec's axis to certify (default: z)",
    )
    p.add_argument(
        "--controller", choices=CONTROLLERS, help="force controller without --spec (default: pi)"
    )
    p.add_argument(
        "--rulebase",
        metavar="RB",
        help="rule base for fuzzy-pi without --spec (default: macvicar_whelan): "
        + RULEBASE_SPEC_HELP,
    )
    p.add_argument("--gains", metavar="GAINS.yaml", help="gains file (default: the defaults)")
    add_plant_argument(p, "simulated robot")
    p.add_argument(
        "--stiffness",
        type=cli_units.stiffnesses,
        required=True,
        metavar=cli_units.STIFFNESSES_METAVAR,
        help=f"contact stiffnesses ({cli_units.STIFFNESS_HELP}; required)",
    )
    p.add_argument(
        "--latency",
        type=cli_units.latencies,
        required=True,
        metavar=cli_units.LATENCIES_METAVAR,
        help=f"{cli_units.LATENCY_HELP} (required)",
    )
    p.add_argument(
        "--contact-sector",
        type=numbers.UNIT_FRACTION,
        default=0.1,
        metavar="SIGMA_MIN",
        help="lower end of the loss-of-contact sector [SIGMA_MIN, 1] (a cell that cannot be "
        "certified with it is tried with contact held)",
    )
    p.add_argument(
        "--fuzzy-region",
        type=numbers.UNIT_FRACTION,
        default=1.0,
        metavar="RHO",
        help="fuzzy-pi: bound the surface over |Ki*e|, |Kp*de| <= RHO (1: the whole universe)",
    )
    p.add_argument("--json", action="store_true", help="print the region as JSON")
    add_quiet_argument(p, progress=False)
    p.add_argument("--png", metavar="region.png", help="draw the region")
    p.add_argument(
        "--simulate",
        action="store_true",
        help="also run each cell in closed loop (compiled loop) and show its outcome",
    )
    p.add_argument(
        "--workers",
        type=numbers.WORKERS,
        default=None,
        help="processes for --simulate (default: every core)",
    )
    p.set_defaults(handler=_stability)


def _stability(args: argparse.Namespace) -> int:
    from fuzzkit.analysis.inner_loop import poor_fit
    from fuzzkit.analysis.regulation import scenario

    if args.png:
        check_output_path(args.png, "PNG file")
    exp = scenario(args.scenario)
    if args.spec is not None:
        region, sim_exp, controller, gains, rulebase = _certify_spec(args, exp)
    else:
        region, sim_exp, controller, gains, rulebase = _certify_assumed(args, exp)
    simulated: list[Any] | None = None
    if args.simulate:
        from fuzzkit.analysis.simulated import simulate_cells

        simulated = simulate_cells(
            sim_exp,
            args.plant,
            controller,
            gains,
            args.stiffness,
            args.latency,
            rulebase=rulebase,
            workers=args.workers,
        )
    if args.png:
        from fuzzkit.viz.stability_figure import write_region_png

        write_region_png(
            region, args.png, None if simulated is None else [s.outcome for s in simulated]
        )
    data = region.as_dict()
    inner = data["model"]["inner_loop"]
    warning = poor_fit(inner["plant"], inner["fit_error_nrmse"])
    if warning is not None:
        print(f"fuzzkit: warning: {warning}", file=sys.stderr)
    if simulated is not None:
        from fuzzkit.loop.result import implementations

        for cell, sim in zip(data["cells"], simulated, strict=True):
            cell["simulated"] = sim.outcome
            cell["controller_impl"] = sim.controller_impl  # what the cell's run itself reports
        data["simulated_with"] = implementations(s.controller_impl for s in simulated)
    if args.json:
        print(json.dumps(data, indent=2))
    else:
        print(_text(data, args))
    return 0


def _certify_spec(
    args: argparse.Namespace, exp: Any
) -> tuple[Any, Any, str, dict[str, float], str]:
    """The region of ``--spec``, and what ``--simulate`` runs: the spec itself."""
    from fuzzkit.analysis.spec_certificate import certify_spec, spec_axis, spec_gains
    from fuzzkit.control.spec_reader import load_spec
    from fuzzkit.errors import ConfigError
    from fuzzkit.loop.task import with_spec

    clash = [f"--{n}" for n in ("controller", "gains", "rulebase") if getattr(args, n)]
    if clash:
        raise ConfigError(f"--spec gives the controller; {', '.join(clash)} cannot be used with it")
    spec = load_spec(args.spec)
    region = certify_spec(
        exp,
        spec,
        args.plant,
        args.stiffness,
        args.latency,
        axis=args.axis,
        fuzzy_region=args.fuzzy_region,
        sigma_min=args.contact_sector,
    )
    gains = spec_gains(spec, spec_axis(spec, args.axis))
    rulebase = spec.rulebase_ref or "macvicar_whelan"
    return region, with_spec(exp, spec), spec.kind, gains, rulebase


def _certify_assumed(
    args: argparse.Namespace, exp: Any
) -> tuple[Any, Any, str, dict[str, float], str]:
    """The region of the controller the options describe (defaults where they are silent)."""
    from fuzzkit.analysis.region import certify_region, effective_gains
    from fuzzkit.analysis.spec_certificate import assumed
    from fuzzkit.cli.simulation import load_gains
    from fuzzkit.errors import ConfigError

    if args.axis is not None:
        raise ConfigError("--axis chooses an axis of --spec; without --spec z is certified")
    controller = args.controller or "pi"
    rulebase = args.rulebase or "macvicar_whelan"
    gains = load_gains(args.gains, controller) if args.gains else {}
    region = certify_region(
        exp,
        controller,
        args.plant,
        args.stiffness,
        args.latency,
        gains=gains,
        rulebase=rulebase,
        fuzzy_region=args.fuzzy_region,
        sigma_min=args.contact_sector,
        deployed=assumed(controller, gains, rulebase),
    )
    return region, exp, controller, effective_gains(controller, gains)[0], rulebase


def _text(data: dict[str, Any], args: argparse.Namespace) -> str:
    """A grid: one row per latency, one column per stiffness."""
    model = data["model"]
    deployed = model["deployed"]
    lines = [
        deployed["text"]
        if deployed.get("assumed")
        else f"certified as shipped: controller spec {deployed['spec']} ({deployed['file']}), "
        f"axis {deployed['axis']}, surface {deployed['surface']}",
        f"{model['scenario']}: {model['controller']} on {model['plant']}, "
        f"inner loop a in [{model['inner_loop']['a'][0]:.4f}, {model['inner_loop']['a'][1]:.4f}]"
        f" (fit error {100 * model['inner_loop']['fit_error_nrmse']:.2g} %)"
        + series_text(model["inner_loop"].get("series_stiffness_n_per_mm")),
    ]
    if "fuzzy" in model:
        fz = model["fuzzy"]
        if "phi" in fz:
            what = _interval(fz["phi"])
        elif "dF_de" in fz:
            what = f"dF/de in {_interval(fz['dF_de'])}, dF/dde in {_interval(fz['dF_dde'])}"
        else:
            what = f"none ({fz.get('why', 'no rest point')})"
        lines.append(f"fuzzy bounds ({fz['bounds']}): {what}; {fz.get('bounds_are', '')}")
    rest = model["equilibrium"]
    if not rest["at_setpoint"]:
        lines.append(f"no cell is certified as settling at the set point: {rest['why']}")
    lines.append(
        "C: certified, contact may be lost; c: certified while contact is held; "
        "n: stable but noise above the band; r: stable around a rest point off the set point; "
        "-: not certified"
        + (
            "; then the simulated outcome (s settled, o oscillating, t tripped)"
            if args.simulate
            else ""
        )
    )
    ks = list(dict.fromkeys(c["stiffness_n_per_mm"] for c in data["cells"]))
    lats = list(dict.fromkeys(tuple(c["latency_periods"]) for c in data["cells"]))
    by = {(c["stiffness_n_per_mm"], tuple(c["latency_periods"])): c for c in data["cells"]}
    lines.append("latency \\ N/mm".ljust(15) + " ".join(f"{k:>{_COL}g}" for k in ks))
    for lat in lats:
        row = []
        for k in ks:
            c = by[(k, lat)]
            mark = "-"
            if c["certified"]:
                mark = "C" if c["contact_sector"] != [1.0, 1.0] else "c"
            elif c["lyapunov_certificate"]:
                mark = "n" if model["equilibrium"]["at_setpoint"] else "r"
            if "simulated" in c:
                mark += c["simulated"][0]
            row.append(f"{mark:>{_COL}}")
        lines.append(f"{latency_text(lat):<15}" + " ".join(row))
    lines.append(
        "region_n (N): the certificate holds locally, for a force up to this far from the set "
        "point (the largest level set of V inside the contact sector and the fuzzy bounds)"
    )
    for lat in lats:
        row = []
        for k in ks:
            c = by[(k, lat)]
            row.append(f"{c['region_n']:>{_COL}.2f}" if c["certified"] else f"{'-':>{_COL}}")
        lines.append(f"{latency_text(lat):<15}" + " ".join(row))
    refused = [c for c in data["cells"] if not c["certified"]]
    if refused:
        lines.append("why not certified:")
    for c in refused:
        why = c.get("why_not_certified") or "no reason recorded"
        where = f"{latency_text(tuple(c['latency_periods']))}, {c['stiffness_n_per_mm']:g} N/mm"
        lines.append(f"  {where}: {why}")
    certified = sum(c["certified"] for c in data["cells"])
    lines.append(f"certified {certified} of {len(data['cells'])} cells")
    if "simulated_with" in data:
        lines.append(f"simulated with: {data['simulated_with']}")
    if "adaptation" in model:
        lines += _adaptation_text(model["adaptation"])
    return "\n".join(lines)


def _adaptation_text(ad: dict[str, Any]) -> list[str]:
    """What the certificate of an adaptive spec assumed, and its verdict on the spec."""
    factors = ", ".join(
        f"{k} N/mm [{lo:g}, {hi:g}]" for k, (lo, hi) in ad["gain_factor_per_stiffness"].items()
    )
    lines = [f"adaptation ({ad['mode']}): the gain factor may switch every period within "
             f"{factors}"]  # fmt: skip
    if "rho" in ad:
        lo, hi = ad["estimate_over_true"]
        lines.append(
            f"  the estimate within k_hat/k in [{lo:g}, {hi:g}] (rho {ad['rho']:g}), projected "
            f"into {ad['range_n_mm']}; "
            + (
                f"the factor min(1, {ad['inverse_n_mm']:g} / k_hat), at k_max until the "
                "estimate is trusted and beyond k_max"
                if ad.get("inverse_n_mm") is not None
                else "the band of k_max until it is trusted, the smallest scale beyond k_max"
            )
        )
    if ad["certified_every_cell"]:
        lines.append(
            "  proved: in every cell, one quadratic Lyapunov function for every factor "
            "sequence in its interval (no dwell); the true stiffness is constant per cell"
        )
        return lines
    lines.append("  refused: not every cell is certified with this adaptation")
    if "rho_needed" in ad:
        needed = ad["rho_needed"]
        lines.append(
            f"  it would be with an estimate within rho {needed:g}"
            if needed is not None
            else "  not even with an exact estimate (rho 0): a band the schedule runs there "
            "(its own, its safe band or its smallest) is not stable"
        )
    return lines


#: Width of a column of the text grids (a stiffness, a verdict, a region_n of 8.2f).
_COL = 8


def _interval(bounds: Any) -> str:
    """``[lo, hi]`` with fixed-width numbers (the JSON keeps every digit)."""
    lo, hi = (float(v) for v in bounds)
    return f"[{lo:9.4f}, {hi:9.4f}]"


def series_text(series_n_per_mm: float | None) -> str:
    """The inner loop's series stiffness as the text output states it ('' without one)."""
    if series_n_per_mm is None:
        return ""
    return (
        f", servo stiffness {series_n_per_mm:.4g} N/mm in series with the contact "
        "(the inner loop's gain at K: k_s / (K + k_s))"
    )
