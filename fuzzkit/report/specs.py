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
    from fuzzkit.studies.batch import RunSpec, run_spec
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
