"""The PI vs fuzzy-PI comparison report: runs, figures, table and the paper's claims checked.

:func:`build_report` runs E1-E3 x {PI, fuzzy-PI} x {default, tuned gains} on one or more plants,
a press-on-the-hammer stiffness study, and writes ``report.md`` with PNG figures (force vs time
per axis with the set point, as the paper's Figs. 7-12; the control surface; overshoot and
settling time against stiffness), the comparison table, the gains, and a claim-by-claim verdict
computed from the numbers by :func:`assess_claims`; plus one ``.rrd`` per run.

Fuzzy-PI runs of the report use the exact inference engine; the tuning (when the report tunes)
uses a lookup table for speed (see ``fuzzkit.studies.tuning``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

from fuzzkit.errors import ConfigError
from fuzzkit.fileio import staged_folder, write_atomic
from fuzzkit.progress import progress_bar

CONTROLLERS = ("pi", "fuzzy-pi")
#: Gains labels, one per comparison protocol (docs/comparison.md): the hand-set defaults, the
#: fuzzy-PI matched to the default PI's small-signal gain (the PI runs its defaults), tuned.
LABELS = ("default", "matched", "tuned")
EXPERIMENT_NAMES = ("E1", "E2", "E3")

#: Stiffnesses of the press study (N/mm).
STUDY_STIFFNESSES_N_PER_MM = (5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0)

#: Differences smaller than these are "no clear difference" when checking a claim:
#: (absolute, relative to the larger value).
OVERSHOOT_TOL = (0.5, 0.10)  # percentage points, fraction
SETTLING_TOL = (0.02, 0.10)  # s, fraction
RMS_TOL = (0.01, 0.10)  # N, fraction
#: E3 "similar": per axis, RMS and settling time within this fraction (or the absolute floor).
SIMILAR_REL = 0.25
SIMILAR_ABS = {"rms_error": 0.05, "settling_time_s": 0.25}

#: Experiments whose force figure gets a zoomed inset of this many seconds from first contact
#: (E1's impact transient lasts about 0.1 s: invisible at its 5 s scale).
ZOOM_S = {"E1": 0.3}
#: Resolution of the report's PNGs.
FIGURE_DPI = 80

Key = tuple[str, str, str, str]  # plant, experiment, controller, gains label


@dataclass(frozen=True, slots=True)
class ClaimResult:
    """One of the paper's claims checked on one plant with one gains set."""

    claim: str
    plant: str
    gains: str
    holds: bool
    verdict: str
    evidence: str


def _axis(summaries: Mapping[Key, Mapping[str, Any]], key: Key, axis: str) -> Mapping[str, Any]:
    data = summaries.get(key)
    if data is None:
        raise ConfigError(f"no run for {'/'.join(key)} (needed by a claim)")
    axes: Mapping[str, Mapping[str, Any]] = data["axes"]
    if axis not in axes:
        raise ConfigError(f"run {'/'.join(key)} has no force-controlled axis {axis}")
    return axes[axis]


def _num(v: Any, never: float = math.inf) -> float:
    return never if v is None else float(v)


def _compare(a: float, b: float, tol: tuple[float, float]) -> int:
    """-1 if a is clearly smaller than b, +1 if clearly larger, 0 within the tolerance."""
    if math.isinf(a) and math.isinf(b):
        return 0
    margin = max(tol[0], tol[1] * max(abs(a), abs(b)) if math.isfinite(max(a, b)) else 0.0)
    if a < b - margin:
        return -1
    if a > b + margin:
        return 1
    return 0


def _fmt(v: Any, unit: str = "", digits: int = 2) -> str:
    if v is None:
        return "never" if unit == " s" else "-"
    return f"{float(v):.{digits}f}{unit}"


def assess_claims(
    summaries: Mapping[Key, Mapping[str, Any]], plant: str, gains: str
) -> list[ClaimResult]:
    """Check the paper's sec. 4.1 conclusions against run summaries.

    Parameters
    ----------
    summaries : ``{(plant, experiment, controller, gains):
    fuzzkit.studies.experiments.summary(...)}``. plant, gains : which plant and gains set
    (``default`` / ``tuned``) to judge.

    Returns
    -------
    One :class:`ClaimResult` per claim, in the paper's order. "Clearly" better means beyond
    the tolerances of this module (``OVERSHOOT_TOL`` ...), else "no clear difference".

    Raises
    ------
    ConfigError
        A run the claims need is missing.
    """

    def k(exp: str, ctrl: str) -> Key:
        return (plant, exp, ctrl, gains)

    out: list[ClaimResult] = []

    def add(claim: str, holds: bool, verdict: str, evidence: str) -> None:
        out.append(ClaimResult(claim, plant, gains, holds, verdict, evidence))

    def verdict_of(sign: int, want: int) -> tuple[bool, str]:
        if sign == want:
            return True, "holds"
        if sign == 0:
            return False, "does not hold (no clear difference)"
        return False, "does not hold (the opposite)"

    # E1: fuzzy-PI less overshoot, faster settling (z, 10 N).
    pi, fz = _axis(summaries, k("E1", "pi"), "z"), _axis(summaries, k("E1", "fuzzy-pi"), "z")
    s = _compare(_num(fz["overshoot_pct"], 0.0), _num(pi["overshoot_pct"], 0.0), OVERSHOOT_TOL)
    holds, v = verdict_of(s, -1)
    add(
        "E1: fuzzy-PI overshoots less than PI",
        holds,
        v,
        f"z overshoot fuzzy-PI {_fmt(fz['overshoot_pct'], ' %', 1)} vs "
        f"PI {_fmt(pi['overshoot_pct'], ' %', 1)}",
    )
    s = _compare(_num(fz["settling_time_s"]), _num(pi["settling_time_s"]), SETTLING_TOL)
    holds, v = verdict_of(s, -1)
    add(
        "E1: fuzzy-PI settles faster than PI",
        holds,
        v,
        f"z settling fuzzy-PI {_fmt(fz['settling_time_s'], ' s')} vs "
        f"PI {_fmt(pi['settling_time_s'], ' s')}",
    )
    # E2: PI finer on small disturbances (RMS while moving), PI larger initial overshoot.
    pi, fz = _axis(summaries, k("E2", "pi"), "z"), _axis(summaries, k("E2", "fuzzy-pi"), "z")
    s = _compare(_num(pi["rms_error"]), _num(fz["rms_error"]), RMS_TOL)
    holds, v = verdict_of(s, -1)
    add(
        "E2: PI has the finer resolution on small disturbances",
        holds,
        v,
        f"z RMS error while moving PI {_fmt(pi['rms_error'], ' N')} vs fuzzy-PI "
        f"{_fmt(fz['rms_error'], ' N')} (steady std {_fmt(pi['steady_state_error_std'], ' N')}"
        f" vs {_fmt(fz['steady_state_error_std'], ' N')})",
    )
    s = _compare(_num(pi["overshoot_pct"], 0.0), _num(fz["overshoot_pct"], 0.0), OVERSHOOT_TOL)
    holds, v = verdict_of(s, 1)
    add(
        "E2: PI overshoots more at the start",
        holds,
        v,
        f"z overshoot PI {_fmt(pi['overshoot_pct'], ' %', 1)} vs "
        f"fuzzy-PI {_fmt(fz['overshoot_pct'], ' %', 1)}",
    )
    # E3: similar results, x behaves like z.
    diffs: list[str] = []
    notes: list[str] = []
    for axis in ("z", "x"):
        pi, fz = _axis(summaries, k("E3", "pi"), axis), _axis(summaries, k("E3", "fuzzy-pi"), axis)
        for metric, unit in (("rms_error", " N"), ("settling_time_s", " s")):
            a, b = _num(pi[metric]), _num(fz[metric])
            tol = (SIMILAR_ABS[metric], SIMILAR_REL)
            what = metric.split("_")[0]
            note = f"{axis} {what} PI {_fmt(pi[metric], unit)} vs {_fmt(fz[metric], unit)}"
            notes.append(note)
            if _compare(a, b, tol) != 0:
                diffs.append(note)
    add(
        "E3: neither controller is better (x behaves like z)",
        not diffs,
        "holds" if not diffs else "does not hold (" + "; ".join(diffs) + ")",
        "; ".join(notes),
    )
    return out


# --------------------------------------------------------------------------------------------
# Markdown
# --------------------------------------------------------------------------------------------


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
                f"{_fmt(m.get('first_contact_s'), ' s')} | {_fmt(m['overshoot_pct'], '', 1)} | "
                f"{_fmt(m['settling_time_s'], ' s')} | "
                f"{_fmt(m['steady_state_error_mean'])} | {_fmt(m['steady_state_error_std'])} | "
                f"{_fmt(m['rms_error'])} | {_fmt(m['peak_force'], '', 1)} | "
                f"{_fmt(m['contact_lost_s'])} |"
            )
    return "\n".join(lines)


def claims_markdown(results: Sequence[ClaimResult]) -> str:
    """The claim-by-claim table as Markdown."""
    lines = [
        "| claim (paper, sec. 4.1) | plant | gains | verdict | numbers |",
        "|---|---|---|---|---|",
    ]
    for c in results:
        verdict = f"**{c.verdict}**" if c.holds else c.verdict
        lines.append(f"| {c.claim} | {c.plant} | {c.gains} | {verdict} | {c.evidence} |")
    return "\n".join(lines)


def claims_summary(results: Sequence[ClaimResult]) -> str:
    """One sentence per claim: in how many of the checked settings it holds."""
    by_claim: dict[str, list[ClaimResult]] = {}
    for c in results:
        by_claim.setdefault(c.claim, []).append(c)
    lines = []
    for claim, rs in by_claim.items():
        n = sum(r.holds for r in rs)
        where = ", ".join(f"{r.plant}/{r.gains}" for r in rs if r.holds)
        if n == len(rs):
            lines.append(f"- {claim}: **holds** in every setting checked ({len(rs)}).")
        elif n == 0:
            lines.append(f"- {claim}: **does not hold** in any setting checked ({len(rs)}).")
        else:
            lines.append(f"- {claim}: holds in {n} of {len(rs)} settings ({where}).")
    return "\n".join(lines)


def claims_conclusion(results: Sequence[ClaimResult]) -> str:
    """One paragraph that follows from the verdict table: which claims hold everywhere, which
    nowhere, and on which settings the rest depend (matched gains being the like-for-like one).
    """
    by_claim: dict[str, list[ClaimResult]] = {}
    for c in results:
        by_claim.setdefault(c.claim, []).append(c)
    always = [k for k, rs in by_claim.items() if all(r.holds for r in rs)]
    never = [k for k, rs in by_claim.items() if not any(r.holds for r in rs)]
    mixed = [k for k in by_claim if k not in always and k not in never]
    parts = [f"Of the paper's {len(by_claim)} claims checked here,"]
    parts.append(
        f"{len(always)} {'holds' if len(always) == 1 else 'hold'} in every setting "
        f"({'; '.join(always)})"
        if always
        else "none holds in every setting"
    )
    parts.append(
        f"and {len(never)} in none ({'; '.join(never)})." if never else "and none fails in all."
    )
    sentences = [" ".join(parts)]
    for claim in mixed:
        rs = by_claim[claim]
        held = [f"{r.plant}/{r.gains}" for r in rs if r.holds]
        matched = [r for r in rs if r.gains == "matched"]
        like = ""
        if matched:
            n_held = sum(r.holds for r in matched)
            where = (
                "holds on every plant"
                if n_held == len(matched)
                else "holds on no plant"
                if n_held == 0
                else f"holds on {n_held} of {len(matched)} plants"
            )
            like = f" With matched small-signal gains (the like-for-like comparison) it {where}."
        sentences.append(
            f"\"{claim}\" depends on the setting: it holds only with {', '.join(held)}.{like}"
        )
    sentences.append(
        "A verdict that changes with the gains is a property of the tuning, not of fuzzy versus "
        "linear control; the latency and stiffness sections below show where each controller "
        "stops being usable."
    )
    return " ".join(sentences)


# --------------------------------------------------------------------------------------------
# The report
# --------------------------------------------------------------------------------------------


def _gains_for(
    ctrl: str,
    gains_dir: Path | None,
    out: Path,
    budget: int,
    rulebase: str,
    seed: int,
    workers: int | None,
    log: IO[str] | None,
) -> tuple[dict[str, float], dict[str, Any]]:
    """Tuned gains of ``ctrl``: read from ``gains_dir`` or tuned now (and saved in out/gains)."""
    from fuzzkit.control.gains import read_gains_file, write_gains

    if gains_dir is not None:
        path = gains_dir / f"{ctrl}.yaml"
        if not path.is_file():
            raise ConfigError(f"{path}: no such gains file (expected pi.yaml and fuzzy-pi.yaml)")
        entries = read_gains_file(path)
        entry = entries.get(ctrl) or entries.get(None)
        if entry is None:
            raise ConfigError(f"{path}: holds no gains for {ctrl}")
        from fuzzkit.studies.experiments import DEFAULT_GAINS

        gains = dict(DEFAULT_GAINS[ctrl])
        gains.update(entry.gains)
        return gains, {**entry.provenance, "source": str(path)}
    from fuzzkit.studies.tuning import progress_callback, tune

    with progress_bar(
        budget, f"tuning {ctrl}", stream=log, quiet=log is None, unit="gain set"
    ) as bar:
        result = tune(
            EXPERIMENT_NAMES,
            ctrl,
            rulebase,
            "planar",
            budget=budget,
            seed=seed,
            workers=workers,
            callback=progress_callback(bar),
        )
    if result.interrupted:  # a report is complete or not written: stop here, not after it
        raise KeyboardInterrupt
    (out / "gains").mkdir(exist_ok=True)
    write_gains(out / "gains" / f"{ctrl}.yaml", result.to_entry(), merge=False)
    entry = result.to_entry()
    return dict(result.gains), {**entry.provenance, "source": f"gains/{ctrl}.yaml"}


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
) -> Path:
    """Run everything and write ``out/report.md``, its PNGs, and one .rrd per run.

    Everything is written into a staging folder beside ``out`` that replaces it only when
    complete (``fileio.staged_folder``): an error or Ctrl-C (KeyboardInterrupt, also raised
    when the tuning is interrupted) leaves the previous report, or none.

    Parameters
    ----------
    out : output folder (created; its parent must exist).
    plants : plant names to run E1-E3 on (tuning and the stiffness study use ``planar``).
    budget : tuning budget per controller when ``gains_dir`` is None.
    gains_dir : folder with ``pi.yaml`` and ``fuzzy-pi.yaml`` (skip tuning).
    rulebase : the fuzzy-PI rule base.
    seed : optimiser seed (sensor noise seed 0, as ``fuzzkit compare``).
    workers : tuning worker processes (None: all cores).
    rrd : write the recordings (``out/rrd/*.rrd``).
    log : where progress bars go (None: nowhere; drawn only on a terminal).
    stiffnesses_n_per_mm : the stiffness study's stiffnesses.

    Returns
    -------
    The path of ``report.md``.

    Raises
    ------
    ConfigError
        Unusable output folder, missing or bad gains files, unknown plant or rule base.
    """
    from fuzzkit.formats.registry import load
    from fuzzkit.studies.experiments import DEFAULT_GAINS, press_experiment
    from fuzzkit.studies.metrics import summary
    from fuzzkit.studies.plants import make_plant
    from fuzzkit.studies.runner import load_surface, run
    from fuzzkit.viz.figures import figure_bytes
    from fuzzkit.viz.study_figures import force_figure, stiffness_figure

    if out.exists() and not out.is_dir():
        raise ConfigError(f"{out}: exists and is not a folder (expected the report folder)")
    parent = out.parent if str(out.parent) else Path(".")
    if not parent.is_dir():
        raise ConfigError(f"{out}: folder {parent} does not exist")
    for p in plants:
        make_plant(p)  # unknown plant: fail before any work
    rb = load(rulebase)
    final = out
    # Everything is written into a staging folder that becomes ``out`` only when complete:
    # Ctrl-C or an error at any point leaves no partial report.
    with staged_folder(final, last="report.md", what="report folder") as out:
        if rrd:
            (out / "rrd").mkdir()

        from fuzzkit.studies.e3_arm6 import resolve
        from fuzzkit.studies.matching import matched_fuzzy_gains

        surface = load_surface(rulebase)
        gains: dict[tuple[str, str], dict[str, float]] = {}
        provenance: dict[str, dict[str, Any]] = {}
        for ctrl in CONTROLLERS:
            gains[(ctrl, "default")] = dict(DEFAULT_GAINS[ctrl])
            g, prov = _gains_for(ctrl, gains_dir, out, budget, rulebase, seed, workers, log)
            gains[(ctrl, "tuned")] = g
            provenance[ctrl] = prov
        gains[("pi", "matched")] = dict(DEFAULT_GAINS["pi"])
        gains[("fuzzy-pi", "matched")] = matched_fuzzy_gains(surface, DEFAULT_GAINS["pi"]).gains
        summaries: dict[Key, dict[str, Any]] = {}
        figures: list[tuple[str, str]] = []
        n_runs = len(CONTROLLERS) * len(LABELS) * (
            len(plants) * len(EXPERIMENT_NAMES) + len(stiffnesses_n_per_mm)
        )
        with progress_bar(n_runs, "runs", stream=log, quiet=log is None, unit="run") as bar:
            for plant in plants:
                for name in EXPERIMENT_NAMES:
                    exp = resolve(name, plant)[0]  # E3 on arm6: the paper's 3-D geometry
                    runs: dict[tuple[str, str], Any] = {}
                    for ctrl in CONTROLLERS:
                        for label in LABELS:
                            bar.set_description(f"{plant} {name} {ctrl} {label}")
                            plant_obj = resolve(name, plant)[1]
                            r = run(
                                exp,
                                plant_obj,
                                ctrl,
                                gains=gains[(ctrl, label)],
                                surface=surface if ctrl == "fuzzy-pi" else None,
                            )
                            runs[(ctrl, label)] = r
                            summaries[(plant, name, ctrl, label)] = summary(r)
                            if rrd:
                                from fuzzkit.viz.traces import write_run_rrd

                                write_run_rrd(
                                    r,
                                    out / "rrd" / f"{plant}_{name}_{ctrl}_{label}.rrd",
                                    plant_obj,
                                )
                            bar.update(1)
                    fname = f"force_{plant}_{name}.png"
                    fig = force_figure(runs, f"{name} on {plant}: {exp.title}", ZOOM_S.get(name))
                    write_atomic(out / fname, figure_bytes(fig, dpi=FIGURE_DPI))
                    figures.append((fname, f"{name} on the {plant} plant"))

            from fuzzkit.viz.surface import write_surface_png

            write_surface_png(rb, out / "surface.png")

            study: dict[tuple[str, str], list[tuple[float, Any]]] = {}
            from fuzzkit.studies.metrics import axis_metrics

            for ctrl in CONTROLLERS:
                for label in LABELS:
                    bar.set_description(f"stiffness study {ctrl} {label}")
                    rows = []
                    for k in stiffnesses_n_per_mm:
                        r = run(
                            press_experiment(k * 1e3),
                            "planar",
                            ctrl,
                            gains=gains[(ctrl, label)],
                            surface=surface if ctrl == "fuzzy-pi" else None,
                        )
                        m = axis_metrics(r, 2)
                        m["tripped"] = float(r.tripped)
                        rows.append((k, m))
                        bar.update(1)
                    study[(ctrl, label)] = rows
        write_atomic(out / "stiffness.png", figure_bytes(stiffness_figure(study), dpi=FIGURE_DPI))

        claims = [c for p in plants for label in LABELS for c in assess_claims(summaries, p, label)]
        text = _markdown(
            plants, rulebase, gains, provenance, summaries, figures, study, claims, rrd, budget
        )
        text += _latency_section(out, surface, log)
        write_atomic(out / "report.md", text)
    return final / "report.md"


#: The latency sweep of the report: gain factors x sensor delays (periods).
LATENCY_FACTORS = (1.0, 2.0, 4.0, 8.0)
LATENCY_DELAYS = tuple(range(7))


def _latency_section(out: Path, surface: Any, stream: IO[str] | None) -> str:
    """Run the latency sweep, write ``latency.png`` and return the report's Latency section."""
    from fuzzkit.studies.experiments import DEFAULT_LATENCY
    from fuzzkit.studies.latency_sweep import stability_map
    from fuzzkit.viz.latency import write_stability_png

    if stream is not None:
        print("latency sweep ...", file=stream, flush=True)
    maps = [
        stability_map(c, LATENCY_FACTORS, LATENCY_DELAYS, surface if c == "fuzzy-pi" else None)
        for c in CONTROLLERS
    ]
    write_stability_png(maps, out / "latency.png")
    md = [
        "",
        "## Latency",
        "",
        f"Default latency of E1-E3: {DEFAULT_LATENCY[0]} period sensor, {DEFAULT_LATENCY[1]} "
        "period command (ABB EGM at 4 ms). Stability boundary: press 10 N on the hammer at "
        "10 N/mm with the default gains times a factor, sensor delay "
        f"{LATENCY_DELAYS[0]}-{LATENCY_DELAYS[-1]} periods; stable means no trip and the last "
        "0.5 s within 0.5 N (`fuzzkit.studies.latency_sweep`).",
        "",
        "![largest stable delay against the gain factor](latency.png)",
        "",
        "| gain factor | " + " | ".join(f"{m.controller}: largest stable delay" for m in maps)
        + " |",
        "|---|" + "---|" * len(maps),
    ]
    top = LATENCY_DELAYS[-1]
    for factor in LATENCY_FACTORS:
        cells = []
        for m in maps:
            b = m.boundary()[factor]
            cells.append("unstable at 0" if b is None else f">= {b}" if b == top else str(b))
        md.append(f"| {factor:g} | " + " | ".join(cells) + " |")
    md.append("")
    return "\n".join(md)


def _markdown(
    plants: Sequence[str],
    rulebase: str,
    gains: Mapping[tuple[str, str], Mapping[str, float]],
    provenance: Mapping[str, Mapping[str, Any]],
    summaries: Mapping[Key, Mapping[str, Any]],
    figures: Sequence[tuple[str, str]],
    study: Mapping[tuple[str, str], list[tuple[float, Any]]],
    claims: Sequence[ClaimResult],
    rrd: bool,
    budget: int,
) -> str:
    plist = ", ".join(plants)
    md = [
        "# PI vs fuzzy-PI force control: comparison report",
        "",
        f"Generated by `fuzzkit report` (plants: {plist}; rule base `{rulebase}`; sensor-noise "
        "seed 0). Every number below is computed by the run that this report describes; the "
        "verdicts are derived from them with the tolerances of `fuzzkit.report.build`.",
        "",
        "## Verdicts at a glance",
        "",
        claims_summary(claims),
        "",
        claims_conclusion(claims),
        "",
        "## Gains",
        "",
        "Default gains are the hand-tuned `DEFAULT_GAINS` (like the paper's, by trial and error, "
        "for 10 N/mm); with them the fuzzy-PI has 1.5x the PI's small-signal gain "
        "(`macvicar_whelan`). Matched gains: the PI runs its defaults and the fuzzy-PI's "
        "scaling factors are derived from them through the rule base's measured slopes at the "
        "origin, so both have the same small-signal gain (docs/comparison.md). Tuned gains "
        "minimise `fuzzkit.studies.tuning.run_cost` "
        "(ITAE of the force error plus penalties for overshoot, force above the safety limit "
        "and contact loss) over "
        "E1-E3 and the stiffnesses listed, on the planar plant.",
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
                if ctrl == "fuzzy-pi"
                else "fuzzkit.studies.experiments.DEFAULT_GAINS",
            }.get(label, prov.get("source"))
            kx = f"{g['kx']:.4g}" if "kx" in g else "-"
            md.append(f"| {ctrl} | {label} | {g['kp']:.4g} | {g['ki']:.4g} | {kx} | ")
            md[-1] += f"{'-' if cost is None else f'{float(cost):.5g}'} | {src} |"
    for ctrl in CONTROLLERS:
        prov = provenance.get(ctrl, {})
        if "experiments" in prov:
            ks = prov.get("stiffness_n_per_mm")
            md.append("")
            md.append(
                f"`{ctrl}` tuned on {', '.join(map(str, prov['experiments']))} at "
                f"{ks} N/mm, seed {prov.get('seed')}, {prov.get('evaluations')} of "
                f"{prov.get('budget')} evaluations"
                + (" (interrupted)" if prov.get("interrupted") else "")
                + "."
            )
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
        "at every stiffness.",
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
                f"{_fmt(m['overshoot_pct'], ' %', 1)}, {_fmt(m['settling_time_s'], ' s')}{tr}"
            )
        md.append(f"| {k:g} | " + " | ".join(cells) + " |")
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
