"""The report's *tuned* setting: both controllers tuned on one problem, and what it buys.

Fair comparison (docs/comparison.md, protocol b): PI and fuzzy-PI are tuned for the same cost
(``fuzzkit.studies.tuning.run_cost``), on the same experiments, over the same stiffnesses and
latencies (:class:`TuningSetup`), so that neither is favoured by the conditions it was tuned
for. The report tunes them itself, or reads a folder of gains files (``pi.yaml``,
``fuzzy-pi.yaml``, written by ``fuzzkit tune`` or an earlier report) and rebuilds the problem
each was tuned on from its provenance. :func:`tuned_vs_default` re-runs every case of that
problem in full with the default and the tuned gains, for the report's per-case table.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

from fuzzkit.errors import ConfigError
from fuzzkit.progress import progress_bar
from fuzzkit.studies.tuning import TuningProblem
from fuzzkit.studies.tuning_check import CaseComparison, compare_gains
from fuzzkit.units import latency_text


@dataclass(frozen=True, slots=True)
class TuningSetup:
    """What both controllers are tuned on: experiments, plant, stiffnesses and latencies.

    The report tunes on the plant it runs (``build_report``: the first of its plants); this
    class's default, ``arm6``, is for callers that name none.
    The per-case table of the report shows where the tuned gains are a compromise.
    """

    experiments: tuple[str, ...] = ("E1", "E2", "E3")
    plant: str = "arm6"
    stiffnesses_n_per_mm: tuple[float, ...] = (5.0, 10.0, 20.0)
    latencies: tuple[tuple[int, int], ...] = ((0, 0), (1, 1), (3, 3))
    #: the admission rule (``fuzzkit.studies.tuning.ADMIT_RULES``): ``experiment`` keeps the
    #: cheapest gain set no worse than the defaults on each experiment's mean over the
    #: stiffness x latency cases. Over 27 cases the stricter ``case`` rule (no worse on every
    #: one) admitted nothing: both controllers kept their defaults, and "tuned" said nothing.
    admit: str = "experiment"

    def describe(self) -> str:
        """One line for the report: what the gains were tuned on."""
        lats = ", ".join(latency_text(p) for p in self.latencies)
        ks = ", ".join(f"{k:g}" for k in self.stiffnesses_n_per_mm)
        n = len(self.experiments) * len(self.stiffnesses_n_per_mm) * len(self.latencies)
        rule = (
            "no worse than the defaults on every case"
            if self.admit == "case"
            else "no worse than the defaults on each experiment's mean over its cases"
        )
        return (
            f"{', '.join(self.experiments)} on {self.plant}, at {ks} N/mm x latency {lats} "
            f"periods ({n} cases; admitted: {rule})"
        )


def setup_from_provenance(prov: Mapping[str, Any], fallback: TuningSetup) -> TuningSetup:
    """The :class:`TuningSetup` a gains file's provenance says its gains were tuned on.

    Files written before latencies were recorded (``latency_periods`` missing or
    ``as defined``) were tuned at each experiment's own latency: one period each way. Gains
    without tuning provenance (written by hand: no ``experiments`` or ``plant``) are compared
    with the defaults on ``fallback``.
    """
    from fuzzkit.studies.experiments import DEFAULT_LATENCY

    exps_raw, plant = prov.get("experiments"), prov.get("plant")
    if not isinstance(exps_raw, list) or not isinstance(plant, str):
        return fallback
    exps = tuple(str(e) for e in exps_raw)
    ks_raw = prov.get("stiffness_n_per_mm")
    ks = tuple(float(k) for k in ks_raw) if isinstance(ks_raw, list) else (10.0,)
    lat_raw = prov.get("latency_periods")
    lats = (
        tuple((int(a), int(b)) for a, b in lat_raw)
        if isinstance(lat_raw, list)
        else (DEFAULT_LATENCY,)
    )
    admit = prov.get("admit")
    return TuningSetup(exps, plant, ks, lats, admit if isinstance(admit, str) else "case")


def problem_of(setup: TuningSetup, controller: str, rulebase: str) -> TuningProblem:
    """The tuning problem of ``controller`` under ``setup``."""
    return TuningProblem.build(
        setup.experiments,
        controller,
        rulebase,
        setup.plant,
        setup.stiffnesses_n_per_mm,
        latencies=setup.latencies,
    )


def gains_for(
    ctrl: str,
    gains_dir: Path | None,
    out: Path,
    setup: TuningSetup,
    budget: int,
    rulebase: str,
    seed: int,
    workers: int | None,
    log: IO[str] | None,
) -> tuple[dict[str, float], dict[str, Any], TuningSetup]:
    """Tuned gains of ``ctrl``, their provenance and the setup they were tuned on: read from
    ``gains_dir`` or tuned now under ``setup`` (and saved in ``out/gains``)."""
    from fuzzkit.control.gains import read_gains_file, write_gains
    from fuzzkit.studies.experiments import DEFAULT_GAINS

    if gains_dir is not None:
        path = gains_dir / f"{ctrl}.yaml"
        if not path.is_file():
            raise ConfigError(f"{path}: no such gains file (expected pi.yaml and fuzzy-pi.yaml)")
        entries = read_gains_file(path)
        entry = entries.get(ctrl) or entries.get(None)
        if entry is None:
            raise ConfigError(f"{path}: holds no gains for {ctrl}")
        gains = dict(DEFAULT_GAINS[ctrl])
        gains.update(entry.gains)
        read_setup = setup_from_provenance(entry.provenance, setup)
        return gains, {**entry.provenance, "source": str(path)}, read_setup
    from fuzzkit.studies.tuning import progress_callback, tune

    with progress_bar(
        budget, f"tuning {ctrl}", stream=log, quiet=log is None, unit="gain set"
    ) as bar:
        result = tune(
            setup.experiments,
            ctrl,
            rulebase,
            setup.plant,
            setup.stiffnesses_n_per_mm,
            budget=budget,
            seed=seed,
            workers=workers,
            callback=progress_callback(bar),
            latencies=setup.latencies,
            admit=setup.admit,
        )
    if result.interrupted:  # a report is complete or not written: stop here, not after it
        raise KeyboardInterrupt
    (out / "gains").mkdir(exist_ok=True)
    entry = result.to_entry()
    write_gains(out / "gains" / f"{ctrl}.yaml", entry, merge=False)
    return dict(result.gains), {**entry.provenance, "source": f"gains/{ctrl}.yaml"}, setup


def tuned_vs_default(
    setup: TuningSetup, ctrl: str, rulebase: str, tuned: Mapping[str, float]
) -> list[CaseComparison]:
    """Every case ``ctrl`` was tuned on, priced and run in full with the defaults and with
    ``tuned`` (independently of the tuning: the costs are computed again here)."""
    from fuzzkit.studies.experiments import DEFAULT_GAINS

    return compare_gains(problem_of(setup, ctrl, rulebase), DEFAULT_GAINS[ctrl], tuned)


def _m(axes: Mapping[str, Mapping[str, Any]], metric: str, unit: str, digits: int) -> str:
    from fuzzkit.report.verdicts import fmt

    return fmt(axes["z"][metric], unit, digits) if "z" in axes else "-"


def tuned_vs_default_markdown(cases: Mapping[str, Sequence[CaseComparison]]) -> str:
    """Per controller and case: tuning cost, z overshoot and z settling, default -> tuned."""
    lines = [
        "| controller | case | cost default -> tuned | change | tuned vs defaults | "
        "z overshoot % | z settle s | trip |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for ctrl, rows in cases.items():
        for c in rows:
            trip = f"{'yes' if c.default_tripped else 'no'} -> {'yes' if c.tuned_tripped else 'no'}"
            lines.append(
                f"| {ctrl} | {c.label} | {c.default_cost:.4g} -> {c.tuned_cost:.4g} | "
                f"{c.cost_change_pct:+.1f} % | {case_verdict(c)} | "
                f"{_m(c.default_axes, 'overshoot_pct', '', 1)} -> "
                f"{_m(c.tuned_axes, 'overshoot_pct', '', 1)} | "
                f"{_m(c.default_axes, 'settling_time_s', ' s', 2)} -> "
                f"{_m(c.tuned_axes, 'settling_time_s', ' s', 2)} | {trip} |"
            )
    return "\n".join(lines)


def case_verdict(c: CaseComparison) -> str:
    """How the tuned gains fare against the defaults on one case, as the per-case table says
    it: **loses to the defaults** when they cost more (or trip where the defaults do not),
    better when they cost less, the same otherwise."""
    if (c.tuned_tripped and not c.default_tripped) or c.tuned_cost > c.default_cost + 1e-12:
        return "**loses to the defaults**"
    return "better" if c.tuned_cost < c.default_cost - 1e-12 else "same"


def worse_cases(cases: Sequence[CaseComparison]) -> list[CaseComparison]:
    """The cases on which the tuned gains cost more than the defaults."""
    return [c for c in cases if c.tuned_cost > c.default_cost + 1e-12]
