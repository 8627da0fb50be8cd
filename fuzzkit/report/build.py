"""The PI vs fuzzy-PI comparison report: runs, figures, tables and the paper's claims checked.

:func:`build_report` runs E1-E3 x {PI, fuzzy-PI} x {default, matched, tuned gains} on one or
more plants, a press-on-the-hammer stiffness study and a latency stability map, judges the
paper's claims per setting (``fuzzkit.report.verdicts``: nominal, and with matched and tuned
gains at every latency and stiffness of ``fuzzkit.report.grid``), and writes ``report.md`` with
PNG figures (force vs time per axis with the set point, as the paper's Figs. 7-12; the control
surface; overshoot and settling time against stiffness; the latency boundary), the comparison
table, the gains and how the tuned ones compare with the defaults per tuning case
(``fuzzkit.report.tuned``); plus one ``.rrd`` per nominal run.

Runs go through ``fuzzkit.studies.batch.run_spec`` (the loop's entry point,
``fuzzkit.loop.run.run_loop``), as ``fuzzkit simulate`` runs them: the generated controller, in
the compiled loop where the plant has one. The stiffness study runs on the report's first
plant (:mod:`fuzzkit.report.stiffness_study`), the latency map on the planar plant.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import IO, Any

from fuzzkit.control.names import KINDS as CONTROLLERS
from fuzzkit.errors import ConfigError
from fuzzkit.fileio import staged_folder, write_atomic
from fuzzkit.progress import progress_bar
from fuzzkit.report import ran
from fuzzkit.report.certified import latency_lines, stiffness_lines
from fuzzkit.report.grid import Condition, RunCache, conditions, grid_summaries, spec
from fuzzkit.report.tuned import (
    TuningSetup,
    gains_for,
    tuned_vs_default,
    tuned_vs_default_markdown,
    worse_cases,
)
from fuzzkit.report.verdicts import (
    NOMINAL,
    OVERSHOOT_TOL,
    RMS_TOL,
    SETTLING_TOL,
    SIMILAR_REL,
    ClaimResult,
    Key,
    assess_claims,
    claims_conclusion,
    claims_markdown,
    claims_summary,
    fmt,
    verdict_matrix_markdown,
)
from fuzzkit.studies.latency_sweep import StabilityMap
from fuzzkit.studies.tuning_check import CaseComparison

#: Gains labels, one per comparison protocol (docs/comparison.md): the hand-set defaults, the
#: fuzzy-PI matched to the default PI's small-signal gain (the PI runs its defaults), tuned.
LABELS = ("default", "matched", "tuned")
#: The gains sets whose verdicts are judged at every latency and stiffness (the fair ones).
SWEPT_LABELS = ("matched", "tuned")
EXPERIMENT_NAMES = ("E1", "E2", "E3")

#: Stiffnesses of the press study (N/mm); the claims are judged at each of them too.
STUDY_STIFFNESSES_N_PER_MM = (5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0)
#: Latencies ((sensor, command) periods) the claims are judged at.
VERDICT_LATENCIES = ((0, 0), (1, 1), (3, 3))

#: Experiments whose force figure gets a zoomed inset of this many seconds from first contact
#: (E1's impact transient lasts about 0.1 s: invisible at its 5 s scale).
ZOOM_S = {"E1": 0.3}
#: Experiments whose force figure adds the force error while moving, zoomed (E2's claim is
#: about that error, a few newtons on a 30 N force).
ERROR_WHILE_MOVING = ("E2",)
#: Resolution of the report's PNGs.
FIGURE_DPI = 80


# --------------------------------------------------------------------------------------------
# The report
# --------------------------------------------------------------------------------------------


def quick_options(plant: str = "planar") -> dict[str, Any]:
    """Keyword arguments of :func:`build_report` for a small, fast report (``fuzzkit report
    --quick``; the tests): tuning on ``plant`` over 10 N/mm x latencies 1:1 and 3:3, the
    stiffness study and the verdicts at 10 and 1000 N/mm, the latency map for 1x and 8x the gains
    up to 3 periods. Every section is there; only the sweeps are shorter."""
    return {
        "stiffnesses_n_per_mm": (10.0, 1000.0),
        "tuning": TuningSetup(
            plant=plant, stiffnesses_n_per_mm=(10.0,), latencies=((1, 1), (3, 3))
        ),
        "verdict_latencies": ((0, 0), (1, 1), (3, 3)),
        "latency_factors": (1.0, 8.0),
        "latency_delays": (0, 1, 2, 3),
    }


def build_report(
    out: Path,
    plants: Sequence[str] = ("planar",),
    budget: int = 40,
    gains_dir: Path | None = None,
    rulebase: str = "macvicar_whelan",
    seed: int = 0,
    workers: int | None = None,
    rrd: bool = True,
    log: IO[str] | None = None,
    stiffnesses_n_per_mm: Sequence[float] = STUDY_STIFFNESSES_N_PER_MM,
    *,
    tuning: TuningSetup | None = None,
    verdict_latencies: Sequence[tuple[int, int]] = VERDICT_LATENCIES,
    latency_factors: Sequence[float] | None = None,
    latency_delays: Sequence[int] | None = None,
    specs: Sequence[Path] = (),
) -> Path:
    """Run everything and write ``out/report.md``, its PNGs, and one .rrd per run.

    Everything is written into a staging folder beside ``out`` that replaces it only when
    complete (``fileio.staged_folder``): an error or Ctrl-C (KeyboardInterrupt, also raised
    when the tuning is interrupted) leaves the previous report, or none.

    Parameters
    ----------
    out : output folder (created; its parent must exist).
    plants : plant names to run E1-E3 on (the stiffness study runs on the first).
    budget : tuning budget per controller when ``gains_dir`` is None.
    gains_dir : folder with ``pi.yaml`` and ``fuzzy-pi.yaml`` (skip tuning).
    rulebase : the fuzzy-PI rule base.
    seed : optimiser seed (sensor noise seed 0, as ``fuzzkit compare``).
    workers : worker processes for the tuning and the runs (None: all cores).
    rrd : write the recordings (``out/rrd/*.rrd``).
    log : where progress bars go (None: nowhere; drawn only on a terminal).
    stiffnesses_n_per_mm : the stiffness study's stiffnesses; the claims are judged at each.
    tuning : what both controllers are tuned on when the report tunes them (None:
        :class:`~fuzzkit.report.tuned.TuningSetup`'s defaults).
    verdict_latencies : the latencies the claims are judged at.
    latency_factors, latency_delays : the latency stability map's gain factors and sensor
        delays (None: :data:`LATENCY_FACTORS`, :data:`LATENCY_DELAYS`).
    specs : controller spec files, each run on E1-E3 per plant in a section of their own.

    Returns
    -------
    The path of ``report.md``.

    Raises
    ------
    ConfigError
        Unusable output folder, missing or bad gains files, unknown plant or rule base.
    """
    from fuzzkit.control.loop_rulebase import load_loop_rulebase
    from fuzzkit.loop.adapter import make_plant
    from fuzzkit.loop.python_loop import load_surface
    from fuzzkit.report.stiffness_study import stiffness_study
    from fuzzkit.studies.batch import experiment_and_plant, run_spec
    from fuzzkit.studies.experiments import DEFAULT_GAINS
    from fuzzkit.studies.metrics import summary
    from fuzzkit.viz.figures import figure_bytes
    from fuzzkit.viz.study_figures import force_figure, stiffness_figure

    if out.exists() and not out.is_dir():
        raise ConfigError(f"{out}: exists and is not a folder (expected the report folder)")
    parent = out.parent if str(out.parent) else Path(".")
    if not parent.is_dir():
        raise ConfigError(f"{out}: folder {parent} does not exist")
    for p in plants:
        make_plant(p)  # unknown plant: fail before any work
    from fuzzkit.control.spec_reader import load_spec

    for path in specs:
        load_spec(path)  # a bad spec: fail before any work
    rb = load_loop_rulebase(rulebase)  # unfit for the loop: fail before any work
    final = out
    # Everything is written into a staging folder that becomes ``out`` only when complete:
    # Ctrl-C or an error at any point leaves no partial report.
    with staged_folder(final, last="report.md", what="report folder") as out:
        if rrd:
            (out / "rrd").mkdir()

        from fuzzkit.studies.matching import small_signal_ratios

        surface = load_surface(rulebase)
        matched, unmatched_note = matched_gains_for_report(surface, rulebase)
        gains: dict[tuple[str, str], dict[str, float]] = {}
        provenance: dict[str, dict[str, Any]] = {}
        setups: dict[str, TuningSetup] = {}
        for ctrl in CONTROLLERS:
            gains[(ctrl, "default")] = dict(DEFAULT_GAINS[ctrl])
            g, prov, setups[ctrl] = gains_for(
                ctrl,
                gains_dir,
                out,
                tuning or TuningSetup(plant=plants[0]),  # tuned on the plant the report runs
                budget,
                rulebase,
                seed,
                workers,
                log,
            )
            gains[(ctrl, "tuned")] = g
            provenance[ctrl] = prov
        gains[("pi", "matched")] = dict(DEFAULT_GAINS["pi"])
        gains[("fuzzy-pi", "matched")] = matched
        cache = RunCache()
        summaries: dict[Key, dict[str, Any]] = {}
        figures: list[tuple[str, str]] = []
        nominal = Condition(NOMINAL)
        n_runs = (
            len(CONTROLLERS)
            * len(LABELS)
            * (len(plants) * len(EXPERIMENT_NAMES) + len(stiffnesses_n_per_mm))
        )
        with progress_bar(n_runs, "runs", stream=log, quiet=log is None, unit="run") as bar:
            for plant in plants:
                for name in EXPERIMENT_NAMES:
                    runs: dict[tuple[str, str], Any] = {}
                    title = ""
                    for ctrl in CONTROLLERS:
                        for label in LABELS:
                            bar.set_description(f"{plant} {name} {ctrl} {label}")
                            s = spec(plant, name, ctrl, gains[(ctrl, label)], nominal, rulebase)
                            r = run_spec(s)  # compiled loop where the plant has one
                            title = r.experiment.title
                            runs[(ctrl, label)] = r
                            summaries[(plant, name, ctrl, label)] = summary(r)
                            cache.put(s, summaries[(plant, name, ctrl, label)])
                            if rrd:
                                from fuzzkit.viz.traces import write_run_rrd

                                drawn = experiment_and_plant(s)[1]  # E3 on arm6: floor, wall
                                write_run_rrd(
                                    r,
                                    out / "rrd" / f"{plant}_{name}_{ctrl}_{label}.rrd",
                                    None if isinstance(drawn, str) else drawn,
                                )
                            bar.update(1)
                    fname = f"force_{plant}_{name}.png"
                    fig = force_figure(
                        runs,
                        f"{name} on {plant}: {title}",
                        ZOOM_S.get(name),
                        error_while_moving=name in ERROR_WHILE_MOVING,
                    )
                    write_atomic(out / fname, figure_bytes(fig, dpi=FIGURE_DPI))
                    figures.append((fname, f"{name} on the {plant} plant"))

            from fuzzkit.viz.surface import write_surface_png

            write_surface_png(rb, out / "surface.png")

            study_plant = plants[0]  # the report's plant (its first --plant)

            def counted(ctrl: str, label: str) -> None:
                bar.set_description(f"stiffness study {ctrl} {label}")
                bar.update(1)

            studied = {(c, lab): gains[(c, lab)] for c in CONTROLLERS for lab in LABELS}
            study = stiffness_study(study_plant, studied, stiffnesses_n_per_mm, rulebase, counted)
        write_atomic(
            out / "stiffness.png",
            figure_bytes(stiffness_figure(study, study_plant), dpi=FIGURE_DPI),
        )

        # The claims at every latency and stiffness, for the fair gains sets.
        conds = conditions(verdict_latencies, stiffnesses_n_per_mm)
        grid_specs = [
            spec(plant, exp, ctrl, gains[(ctrl, label)], c, rulebase)
            for c in conds
            for plant in plants
            for exp in EXPERIMENT_NAMES
            for ctrl in CONTROLLERS
            for label in SWEPT_LABELS
        ]
        with progress_bar(
            cache.missing(grid_specs),
            "verdict runs",
            stream=log,
            quiet=log is None,
            unit="run",
        ) as bar:
            grid = grid_summaries(
                cache,
                plants,
                EXPERIMENT_NAMES,
                CONTROLLERS,
                gains,
                SWEPT_LABELS,
                conds,
                rulebase,
                workers,
                lambda n: bar.update(n - bar.n),
            )
        claims = [c for p in plants for label in LABELS for c in assess_claims(summaries, p, label)]
        swept = [
            c
            for cond in conds
            for p in plants
            for label in SWEPT_LABELS
            for c in assess_claims(grid[cond.label], p, label, cond.label)
        ]
        if log is not None:
            print("tuned vs default per case ...", file=log, flush=True)
        per_case = {
            ctrl: tuned_vs_default(setups[ctrl], ctrl, rulebase, gains[(ctrl, "tuned")])
            for ctrl in CONTROLLERS
        }
        text = _markdown(
            plants,
            rulebase,
            gains,
            provenance,
            setups,
            per_case,
            summaries,
            figures,
            study,
            claims,
            swept,
            conds,
            rrd,
            small_signal_ratios(surface),
            unmatched_note,
        )
        from fuzzkit.report.specs import adaptive_rows, adaptive_section, spec_rows, spec_section

        with progress_bar(
            len(specs) * len(plants) * len(EXPERIMENT_NAMES),
            "controller specs",
            stream=log,
            quiet=log is None or not specs,
            unit="run",
        ) as bar:
            spec_runs = spec_rows(specs, plants, EXPERIMENT_NAMES, lambda: bar.update(1))
        text += "\n".join(spec_section(spec_runs))
        with progress_bar(
            len(specs) * len(plants) * len(EXPERIMENT_NAMES),
            "adaptive against fixed",
            stream=log,
            quiet=log is None or not specs,
            unit="pair",
        ) as bar:
            pairs = adaptive_rows(specs, plants, EXPERIMENT_NAMES, lambda: bar.update(1))
        text += "\n".join(adaptive_section(pairs))
        latency_text, maps = _latency_section(
            out,
            log,
            tuple(latency_factors or LATENCY_FACTORS),
            tuple(latency_delays or LATENCY_DELAYS),
            rulebase,
        )
        text += latency_text
        records = [
            *(ran.record("E1-E3", d, gains=k[3]) for k, d in summaries.items()),
            *(
                ran.record("stiffness study", m, controller=c, gains=lab, stiffness=k)
                for (c, lab), rows in study.items()
                for k, m in rows
            ),
            *(
                ran.record("verdict grid", d, gains=k[3], condition=cond)
                for cond, by_key in grid.items()
                for k, d in by_key.items()
            ),
            *(ran.record("controller specs", d, spec=d["spec"]) for d in spec_runs),
            *(
                ran.record(f"adaptive against fixed ({which})", p[which], spec=p["spec"])
                for p in pairs
                for which in ("adaptive", "fixed")
            ),
            *(
                ran.record("latency sweep", {"controller_impl": m.controller_impl},
                           controller=m.controller, runs=len(m.factors) * len(m.delays))
                for m in maps
            ),
        ]  # fmt: skip
        text += "\n".join(ran.section(records))
        write_atomic(out / "runs.json", ran.runs_json(records))
        write_atomic(out / "report.md", text)
    return final / "report.md"


#: The latency sweep of the report: gain factors x sensor delays (periods).
LATENCY_FACTORS = (1.0, 2.0, 4.0, 8.0)
LATENCY_DELAYS = tuple(range(7))


def _latency_section(
    out: Path,
    stream: IO[str] | None,
    factors: tuple[float, ...],
    delays: tuple[int, ...],
    rulebase: str = "macvicar_whelan",
) -> tuple[str, list[StabilityMap]]:
    """Run the latency sweep, write ``latency.png`` and return the report's Latency section
    and the maps."""
    from fuzzkit.studies.experiments import DEFAULT_LATENCY
    from fuzzkit.studies.latency_sweep import stability_map
    from fuzzkit.viz.latency import write_stability_png

    if stream is not None:
        print("latency sweep ...", file=stream, flush=True)
    maps = [stability_map(c, factors, delays, rulebase) for c in CONTROLLERS]
    write_stability_png(maps, out / "latency.png")
    md = [
        "",
        "## Latency",
        "",
        f"Default latency of E1-E3: {DEFAULT_LATENCY[0]} period sensor, {DEFAULT_LATENCY[1]} "
        "period command (ABB EGM at 4 ms). Stability boundary: press 10 N on the hammer at "
        "10 N/mm with the default gains times a factor, sensor delay "
        f"{delays[0]}-{delays[-1]} periods, each run the generated controller; stable means "
        "no trip and the last 0.5 s within 0.5 N on every force-controlled axis "
        "(`fuzzkit.studies.outcome.end_state`).",
        "",
        "![largest stable delay against the gain factor](latency.png)",
        "",
        "| gain factor | "
        + " | ".join(f"{m.controller}: largest stable delay" for m in maps)
        + " |",
        "|---|" + "---|" * len(maps),
    ]
    top = delays[-1]
    for factor in factors:
        cells = []
        for m in maps:
            b = m.boundary()[factor]
            cells.append("unstable at 0" if b is None else f">= {b}" if b == top else str(b))
        md.append(f"| {factor:g} | " + " | ".join(cells) + " |")
    md += latency_lines(maps, rulebase)
    md.append("")
    return "\n".join(md), maps


def comparison_markdown(summaries: Mapping[Key, Mapping[str, Any]]) -> str:
    """The comparison table (one row per run and axis) as Markdown."""
    head = (
        "| plant | exp | axis | set N | controller | gains | contact s | overshoot % | "
        "settle s | ss mean N | ss std N | rms moving N | peak N | lost s |"
    )
    lines = [head, "|" + "---|" * 14]
    for (plant, exp, ctrl, label), data in summaries.items():
        for axis, m in data["axes"].items():
            lines.append(
                f"| {plant} | {exp} | {axis} | {m['setpoint']:g} | {ctrl} | {label} | "
                f"{fmt(m.get('first_contact_s'), ' s')} | {fmt(m['overshoot_pct'], '', 1)} | "
                f"{fmt(m['settling_time_s'], ' s')} | "
                f"{fmt(m['steady_state_error_mean'])} | {fmt(m['steady_state_error_std'])} | "
                f"{fmt(m['rms_error'])} | {fmt(m['peak_force'], '', 1)} | "
                f"{fmt(m['contact_lost_s'])} |"
            )
    return "\n".join(lines)


def matched_gains_for_report(surface: Any, rulebase: str) -> tuple[dict[str, float], str | None]:
    """The fuzzy-PI's "matched" gains: matched to the default PI's small-signal gain
    (``studies.matching.matched_fuzzy_gains``); or, for a rule base with no small-signal gain
    at the origin, where there is nothing to match, the default gains and the sentence that
    says so (the report states it where it defines its gains)."""
    from fuzzkit.studies.experiments import DEFAULT_GAINS
    from fuzzkit.studies.matching import has_small_signal_gain, matched_fuzzy_gains, measure_slopes

    slopes = measure_slopes(surface)
    if has_small_signal_gain(slopes):
        return matched_fuzzy_gains(surface, DEFAULT_GAINS["pi"]).gains, None
    return dict(DEFAULT_GAINS["fuzzy-pi"]), (
        f"`{rulebase}` has no small-signal gain at the origin (dF/de = {slopes.e:.3g}, "
        f'dF/dde = {slopes.de:.3g}), so there is nothing to match: its "matched" fuzzy-PI '
        "runs the default gains, and the matched verdicts compare the defaults"
    )


def default_gain_sentence(rulebase: str, ratios: tuple[float, float]) -> str:
    """What the default gains give the fuzzy-PI running ``rulebase``, from its small-signal gain
    ratios to the PI's ``(proportional, integral)`` (``studies.matching.small_signal_ratios``)."""

    def times(r: float) -> str:
        return "no" if r == 0.0 else f"{r:.3g}x the PI's"

    p, i = ratios
    if math.isclose(p, i, rel_tol=1e-3):
        what = f"{times(p)} small-signal gain"
    else:
        what = f"{times(p)} proportional and {times(i)} integral small-signal gain"
    return (
        f"the fuzzy-PI has {what} (`{rulebase}`: its control surface's slopes at the origin, "
        "where the saturated sum that the default gains are set for has slope 1)"
    )


def _markdown(
    plants: Sequence[str],
    rulebase: str,
    gains: Mapping[tuple[str, str], Mapping[str, float]],
    provenance: Mapping[str, Mapping[str, Any]],
    setups: Mapping[str, TuningSetup],
    per_case: Mapping[str, Sequence[CaseComparison]],
    summaries: Mapping[Key, Mapping[str, Any]],
    figures: Sequence[tuple[str, str]],
    study: Mapping[tuple[str, str], list[tuple[float, Any]]],
    claims: Sequence[ClaimResult],
    swept: Sequence[ClaimResult],
    conds: Sequence[Condition],
    rrd: bool,
    gain_ratios: tuple[float, float],
    unmatched_note: str | None = None,
) -> str:
    plist = ", ".join(plants)
    everything = [*claims, *(c for c in swept if c.condition != NOMINAL)]
    same_setup = setups["pi"] == setups["fuzzy-pi"]
    md = [
        "# PI vs fuzzy-PI force control: comparison report",
        "",
        f"Generated by `fuzzkit report` (plants: {plist}; rule base `{rulebase}`; sensor-noise "
        "seed 0). Every number below is computed by the run that this report describes; the "
        "verdicts are derived from them with the tolerances of `fuzzkit.report.verdicts`.",
        "",
        "## Verdicts at a glance",
        "",
        "Each claim is judged per setting: plant x gains (default, matched, tuned) at the "
        "nominal condition (latency 1:1 periods, 10 N/mm), and plant x gains (matched, "
        "tuned) at "
        + ", ".join(c.label for c in conds if c.label != NOMINAL)
        + " (section Verdicts per setting).",
        "",
        claims_summary(everything),
        "",
        claims_conclusion(everything),
        "",
        "## Gains",
        "",
        "Default gains are the hand-tuned `DEFAULT_GAINS` (like the paper's, by trial and error, "
        f"for 10 N/mm); with them {default_gain_sentence(rulebase, gain_ratios)}. "
        + (
            f"Matched gains: {unmatched_note}. "
            if unmatched_note
            else "Matched gains: the PI runs its defaults and the fuzzy-PI's "
            "scaling factors are derived from them through the rule base's measured slopes at "
            "the origin, so both have the same small-signal gain (docs/comparison.md). "
        )
        + "Tuned gains "
        "minimise `fuzzkit.studies.tuning.run_cost` "
        "(ITAE of the force error plus penalties for overshoot, force above the safety limit "
        "and contact loss) over every case of "
        + (
            f"the same problem for both controllers: {setups['pi'].describe()}. E3 on arm6 is "
            "the paper's 3-D E3 (path along y over a rough floor beside a side wall), as in "
            "the verdicts"
            if same_setup
            else "the problems listed below (not the same for both controllers: not a fair "
            "comparison)"
        )
        + ".",
        "",
        "| controller | gains | kp | ki | kx | tuning cost | source |",
        "|---|---|---|---|---|---|---|",
    ]
    for ctrl in CONTROLLERS:
        prov = provenance.get(ctrl, {})
        for label in LABELS:
            g = gains[(ctrl, label)]
            cost = {"default": prov.get("default_cost"), "tuned": prov.get("cost")}.get(label)
            src = {
                "default": "fuzzkit.studies.experiments.DEFAULT_GAINS",
                "matched": "fuzzkit.studies.matching (measured slopes)"
                if ctrl == "fuzzy-pi" and not unmatched_note
                else "fuzzkit.studies.experiments.DEFAULT_GAINS",
            }.get(label, prov.get("source"))
            kx = f"{g['kx']:.4g}" if "kx" in g else "-"
            md.append(f"| {ctrl} | {label} | {g['kp']:.4g} | {g['ki']:.4g} | {kx} | ")
            md[-1] += f"{'-' if cost is None else f'{float(cost):.5g}'} | {src} |"
    for ctrl in CONTROLLERS:
        prov = provenance.get(ctrl, {})
        md.append("")
        if "experiments" not in prov:
            md.append(
                f"`{ctrl}` tuned gains from {prov.get('source')} carry no tuning provenance: "
                f"compared with the defaults on the report's tuning cases, "
                f"{setups[ctrl].describe()}."
            )
            continue
        md.append(
            f"`{ctrl}` tuned on {setups[ctrl].describe()}, seed {prov.get('seed')}, "
            f"{prov.get('evaluations')} of {prov.get('budget')} evaluations"
            + (" (interrupted)" if prov.get("interrupted") else "")
            + (" (no candidate beat the defaults: kept them)" if prov.get("kept_defaults") else "")
            + "."
        )
    md += [
        "",
        "### Tuned against the defaults, per stiffness and latency",
        "",
        "Every case the gains were tuned on, priced again here with the tuning cost (over the "
        "tuning's horizon) and run in full: z overshoot and settling, default -> tuned.",
        "",
        tuned_vs_default_markdown(per_case),
        "",
    ]
    for ctrl, cases in per_case.items():
        worse = worse_cases(cases)
        md.append(
            f"`{ctrl}`: tuned no worse than the defaults on all {len(cases)} cases."
            if not worse
            else f"`{ctrl}`: tuned worse than the defaults on {len(worse)} of {len(cases)} cases "
            f"({', '.join(f'{c.label} {c.cost_change_pct:+.1f} %' for c in worse)})."
        )
        md.append("")
    md += [
        "## Verdicts per setting",
        "",
        "The paper's claims with matched and with tuned gains at each latency (at 10 N/mm) and "
        "each stiffness of the stiffness study (at latency 1:1): **yes** holds, no does not "
        "hold, no (=) no clear difference, trip not judged because that controller (PI, "
        "fuzzy-PI or both) tripped the safety limit and stopped. The numbers behind every cell "
        "follow the tables.",
        "",
    ]
    for plant in plants:
        md += [f"### {plant}", "", verdict_matrix_markdown(swept, plant), ""]
    md += [
        "<details><summary>The numbers behind every cell</summary>",
        "",
        claims_markdown(swept),
        "",
        "</details>",
        "",
    ]
    md += [
        "",
        "## Comparison table",
        "",
        "True contact force, each axis measured from its own first contact (`contact s`: the "
        "normal force credited to that axis, friction excluded, reaches the engage threshold; "
        "'never' when no surface faces the axis, which is then measured from the run's first "
        "contact); overshoot past the set point in % of it (where the path keeps driving into "
        "the surface, the ramp-following error); settling into the 5 % band (0.5 N for 0 N) "
        "from the end of the approach (the first contact, or when the path stops moving along "
        "the axis); steady state over the last second; RMS error while the path moves; peak "
        "force; time without touching a surface facing the axis after its first contact. "
        "Definitions: docs/simulation.md, section Results.",
        "",
        comparison_markdown(summaries),
        "",
        "## The paper's claims, checked",
        "",
        "Tolerances: overshoot differences below "
        f"{OVERSHOOT_TOL[0]} points or {OVERSHOOT_TOL[1]:.0%}, settling below "
        f"{SETTLING_TOL[0]} s or {SETTLING_TOL[1]:.0%}, RMS below {RMS_TOL[0]} N or "
        f"{RMS_TOL[1]:.0%} count as no clear difference; E3 is 'similar' when RMS and settling "
        f"of every axis agree within {SIMILAR_REL:.0%}.",
        "",
        claims_markdown(claims),
        "",
        "## Force against time (cf. the paper's Figs. 7-12)",
        "",
    ]
    for fname, caption in figures:
        md += [f"![{caption}]({fname})", ""]
    md += [
        "## Control surface",
        "",
        f"![control surface of {rulebase}](surface.png)",
        "",
        "## Environment stiffness",
        "",
        "Press 10 N on E1's hammer from 0.2 mm above it (`press_experiment`), the same gains "
        f"at every stiffness, on the {plants[0]} plant (the report's first `--plant`), each "
        "run the generated controller as `fuzzkit simulate` runs it.",
        "",
        "![overshoot and settling time against stiffness](stiffness.png)",
        "",
        "| stiffness N/mm | " + " | ".join(f"{c} {lab}" for c, lab in study) + " |",
        "|---|" + "---|" * len(study),
    ]
    ks = [k for k, _ in next(iter(study.values()))]
    for i, k in enumerate(ks):
        cells = []
        for rows in study.values():
            m = rows[i][1]
            tr = " (tripped)" if m.get("tripped") else ""
            cells.append(
                f"{fmt(m['overshoot_pct'], ' %', 1)}, {fmt(m['settling_time_s'], ' s')}{tr}"
            )
        md.append(f"| {k:g} | " + " | ".join(cells) + " |")
    md += stiffness_lines(study, gains, rulebase, plants[0])
    md += ["", "## Recordings", ""]
    if rrd:
        md.append(
            "One Rerun recording per run in `rrd/` (`rerun rrd/planar_E1_pi_tuned.rrd`); "
            "recordings are not committed (`*.rrd` is ignored by git): regenerate them with "
            "`fuzzkit report`."
        )
    else:
        md.append("Not written (`--no-rrd`).")
    md.append("")
    return "\n".join(md)
