"""The report's stiffness study: press 10 N on E1's hammer (``press_experiment``) at each
stiffness with the same gains, on the report's plant, through the loop's entry point."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

#: One row per stiffness: (N/mm, the z axis's metrics with ``tripped`` and the run's
#: ``controller_impl``).
StudyRows = list[tuple[float, Any]]


def stiffness_study(
    plant: str,
    gains: Mapping[tuple[str, str], Mapping[str, float]],
    stiffnesses_n_per_mm: Sequence[float],
    rulebase: str,
    on_run: Callable[[str, str], None] | None = None,
) -> dict[tuple[str, str], StudyRows]:
    """Per ``(controller, gains label)`` of ``gains``, the press at every stiffness on
    ``plant``, run as ``fuzzkit simulate`` runs it (:func:`fuzzkit.loop.run.run_loop`: the
    generated controller, in the plant's compiled loop where it has one); ``on_run(controller,
    label)`` is called after each run (the progress bar)."""
    from fuzzkit.loop.run import run_loop
    from fuzzkit.loop.spec import RunSpec
    from fuzzkit.studies.batch import gains_items
    from fuzzkit.studies.experiments import press_experiment
    from fuzzkit.studies.metrics import axis_metrics

    study: dict[tuple[str, str], StudyRows] = {}
    for (ctrl, label), g in gains.items():
        rows: StudyRows = []
        for k in stiffnesses_n_per_mm:
            press = press_experiment(k * 1e3)
            run = RunSpec(press.name, ctrl, plant, gains=gains_items(g), rulebase=rulebase)
            r = run_loop(run, press, plant)
            m: dict[str, Any] = {**axis_metrics(r, 2), "tripped": float(r.tripped)}
            m["controller_impl"] = r.controller_impl
            rows.append((k, m))
            if on_run is not None:
                on_run(ctrl, label)
        study[(ctrl, label)] = rows
    return study
