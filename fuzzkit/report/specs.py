"""The report's section on controller specs: each given spec run on E1-E3 per plant.

A spec (``docs/controller.md``) is what ships; the report runs it as it is (its gains, limits,
safety and sensor front end) on the same experiments as the gain sets, and says which loop ran
it (``docs/controller.md``, "what runs where").
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any


def _fmt(value: Any, digits: int) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


def spec_rows(
    specs: Sequence[Path],
    plants: Sequence[str],
    experiments: Sequence[str],
    progress: Callable[[], None] | None = None,
) -> list[dict[str, Any]]:
    """One summary (``fuzzkit simulate --json``'s) per spec x plant x experiment, in order."""
    from fuzzkit.loop.spec import RunSpec
    from fuzzkit.studies.batch import run_spec
    from fuzzkit.studies.metrics import summary

    rows = []
    for path in specs:
        for plant in plants:
            for name in experiments:
                data = summary(run_spec(RunSpec(name, plant=plant, controller_spec=str(path))))
                data["spec"] = str(path)
                rows.append(data)
                if progress is not None:
                    progress()
    return rows


def spec_section(rows: Sequence[dict[str, Any]]) -> list[str]:
    """The markdown lines of the section (empty without rows)."""
    if not rows:
        return []
    md = [
        "## Controller specs",
        "",
        "Each spec runs as it ships: its gains, correction limits, safety logic and sensor front "
        "end (`docs/controller.md`), on the experiments' worlds with their task replaced by the "
        "spec's axes and set points.",
        "",
        "| spec | plant | exp | axis | set N | overshoot % | settling s | steady error N | "
        "peak N | tripped | loop |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        for axis, m in r["axes"].items():
            md.append(
                f"| `{r['spec']}` | {r['plant']} | {r['experiment']} | {axis} | "
                f"{m['setpoint']:g} | {_fmt(m['overshoot_pct'], 1)} | "
                f"{_fmt(m['settling_time_s'], 2)} | {_fmt(m['steady_state_error_mean'], 3)} | "
                f"{_fmt(m['peak_force_true'], 1)} | {'yes' if r['tripped'] else 'no'} | "
                f"{r['loop'].split(' (')[0]} |"
            )
    return [*md, ""]


def adaptive_rows(
    specs: Sequence[Path],
    plants: Sequence[str],
    experiments: Sequence[str],
    progress: Callable[[], None] | None = None,
) -> list[dict[str, Any]]:
    """For each spec that adapts its gains, per plant x experiment: the summary of the spec and
    of the same spec with fixed gains (``{"spec", "plant", "experiment", "adaptive",
    "fixed"}``), both running the spec's generated controller through the loop's one entry
    point (the compiled loop where the plant has one)."""
    import dataclasses

    from fuzzkit.control.adaptation_spec import NONE
    from fuzzkit.control.spec_reader import load_spec
    from fuzzkit.loop.run import run_loop
    from fuzzkit.loop.spec import RunSpec
    from fuzzkit.studies.batch import experiment_and_plant
    from fuzzkit.studies.experiments import with_spec
    from fuzzkit.studies.metrics import summary

    def run(name: str, plant: str, cs: Any) -> dict[str, Any]:
        exp, own = experiment_and_plant(RunSpec(name, plant=plant))
        rulebase = cs.rulebase_source or "macvicar_whelan"  # a pi: unused
        spec = RunSpec(name, controller=cs.kind, plant=plant, rulebase=rulebase)
        return summary(run_loop(spec, with_spec(exp, cs), own))

    rows = []
    for path in specs:
        spec = load_spec(path)
        if spec.adaptation.mode == "none":
            continue
        twins = (("adaptive", spec), ("fixed", dataclasses.replace(spec, adaptation=NONE)))
        for plant in plants:
            for name in experiments:
                pair = {label: run(name, plant, s) for label, s in twins}
                rows.append({"spec": str(path), "plant": plant, "experiment": name, **pair})
                if progress is not None:
                    progress()
    return rows


def adaptive_verdict(adaptive: dict[str, Any], fixed: dict[str, Any], axis: str) -> str:
    """``better``, ``worse`` or ``same`` for the adaptive run of one setting and axis: a run that
    does not trip beats one that trips; then one that settles beats one that does not; then the
    shorter settling time wins when it is shorter by more than 10 % (else ``same``)."""
    key_a = (not adaptive["tripped"], adaptive["axes"][axis]["settling_time_s"])
    key_f = (not fixed["tripped"], fixed["axes"][axis]["settling_time_s"])
    if key_a[0] != key_f[0]:
        return "better" if key_a[0] else "worse"
    if not key_a[0]:
        return "same"
    if (key_a[1] is None) != (key_f[1] is None):
        return "better" if key_a[1] is not None else "worse"
    if key_a[1] is None or key_f[1] is None:
        return "same"
    if key_a[1] < 0.9 * key_f[1]:
        return "better"
    if key_f[1] < 0.9 * key_a[1]:
        return "worse"
    return "same"


def adaptive_section(rows: Sequence[dict[str, Any]]) -> list[str]:
    """The markdown lines of "Adaptive against fixed scaling factors" (empty without rows)."""
    if not rows:
        return []
    md = [
        "## Adaptive against fixed scaling factors",
        "",
        "The paper's sec. 3.2.4 sets the scaling factors by trial and error for one environment. "
        "Each spec with an `adaptation:` section runs beside the same spec with fixed gains "
        '(`docs/controller.md`, "Adaptation"), both as the spec\'s generated controller; per '
        "setting the adaptive run is better when it does not trip and the fixed one does, then "
        "when it settles and the fixed one does not, "
        "then when it settles more than 10 % sooner (worse the other way round, else same).",
        "",
        "| spec | plant | exp | axis | adaptive: settling s, peak N, tripped | k est N/mm | "
        "fixed: settling s, peak N, tripped | adaptive is | loop |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    counts = {"better": 0, "worse": 0, "same": 0}
    for r in rows:
        a, f = r["adaptive"], r["fixed"]
        for axis, m in a["axes"].items():
            verdict = adaptive_verdict(a, f, axis)
            counts[verdict] += 1
            k = (a.get("stiffness_estimate_n_mm") or {}).get(axis)
            fm = f["axes"][axis]
            md.append(
                f"| `{r['spec']}` | {r['plant']} | {r['experiment']} | {axis} | "
                f"{_fmt(m['settling_time_s'], 2)}, {_fmt(m['peak_force_true'], 1)}, "
                f"{'yes' if a['tripped'] else 'no'} | {_fmt(k, 1)} | "
                f"{_fmt(fm['settling_time_s'], 2)}, {_fmt(fm['peak_force_true'], 1)}, "
                f"{'yes' if f['tripped'] else 'no'} | {verdict} | "
                f"{a['loop'].split(' (')[0]} |"
            )
    total = sum(counts.values())
    md += [
        "",
        f"Adaptive better in {counts['better']}, worse in {counts['worse']}, the same in "
        f"{counts['same']} of {total} settings (axis x experiment x plant). The stiffness sweep "
        'against fixed gains is in `docs/controller.md` ("Adaptive against fixed, measured").',
        "",
    ]
    return md
