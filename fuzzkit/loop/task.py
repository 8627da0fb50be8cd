"""The experiment model: a world (:class:`~fuzzkit.plants.contract.Scenario`) plus the
force-control task in it. Scenario files (:mod:`fuzzkit.studies.scenario_file`) build it."""

from __future__ import annotations

from dataclasses import dataclass, replace

from fuzzkit.control.names import AXES
from fuzzkit.control.spec import AxisSpec, ControllerSpec, Limits, Safety
from fuzzkit.errors import ConfigError
from fuzzkit.fuzzy.model import RuleBase
from fuzzkit.plants.contract import Scenario

#: Default (sensor, command) latency in periods of 4 ms: one period each way, as on an ABB EGM
#: cell (docs/simulation.md, "Latency", says why).
DEFAULT_LATENCY: tuple[int, int] = (1, 1)


#: Default gains, tuned by hand (like the paper's, "by trial and error") for the default contact
#: stiffness of 10 N/mm and a 4 ms period. PI: metres per newton. Fuzzy-PI: Ki scales e and Kp
#: scales de (1/N), Kx scales the output (m per step). Small-signal equivalence with the
#: saturated-sum table: Kx*Ki = 1e-5 m/N = PI ki, Kx*Kp = 4e-5 m/N = PI kp.
DEFAULT_GAINS: dict[str, dict[str, float]] = {
    "pi": {"kp": 4.0e-5, "ki": 1.0e-5, "u_min": -0.05, "u_max": 0.05},
    "fuzzy-pi": {"kp": 0.2, "ki": 0.05, "kx": 2.0e-4, "u_min": -0.05, "u_max": 0.05},
}


@dataclass(frozen=True, slots=True)
class Experiment:
    """One experiment: a world plus what the force loop must do in it.

    ``setpoints`` and ``selection`` are per task axis (x, y, z). ``engage_threshold_n``: the
    force loop takes over when a measured force exceeds it (None: active from the start).
    ``hold_path_on_contact``: the nominal path stops when the loop takes over.
    ``steady_window_s``: the final stretch used for steady-state statistics.
    ``latency_periods``: (sensor-to-controller, controller-to-motion) delays in periods.
    ``engage_samples``: consecutive samples above the threshold needed to engage. ``fault``:
    the sensor fault kind injected by default (a name of ``fuzzkit.loop.faults.FAULTS``).
    ``controller_spec``: the controller the experiment runs (a scenario's ``controller:``, or
    ``--spec``; :func:`fuzzkit.studies.experiments.with_spec`); its axes, set points, safety
    limit and engagement are the fields above. None: the controller named on the command line,
    with the default or given gains.
    """

    name: str
    title: str
    scenario: Scenario
    setpoints: tuple[float, float, float]
    selection: tuple[bool, bool, bool]
    force_limit_n: float
    engage_threshold_n: float | None = 1.0
    hold_path_on_contact: bool = False
    steady_window_s: float = 1.0
    latency_periods: tuple[int, int] = DEFAULT_LATENCY
    engage_samples: int = 3
    fault: str = "none"
    controller_spec: ControllerSpec | None = None


def with_spec(exp: Experiment, spec: ControllerSpec) -> Experiment:
    """``exp`` run by the controller of ``spec``: the spec's axes, set points, safety limit and
    engagement replace the experiment's (the path hold stays the scenario's).

    Raises
    ------
    ConfigError
        The spec's sample period is not the scenario's.
    """
    period = exp.scenario.period_s
    if spec.period_s != period:
        raise ConfigError(
            f"controller spec {spec.name!r} runs every {spec.period_s:g} s, scenario "
            f"{exp.name} every {period:g} s; the periods must agree"
        )
    return replace(
        exp,
        setpoints=spec.setpoints,
        selection=spec.selection,
        force_limit_n=spec.safety.limit_n,
        engage_threshold_n=spec.safety.engage_threshold_n,
        engage_samples=spec.safety.engage_samples,
        controller_spec=spec,
    )


#: Correction limits a spec gets when its gains name none (m; m per period): the examples'.
DEFAULT_CORRECTION_M = 0.05
DEFAULT_STEP_M = 0.001


def spec_for(
    exp: Experiment,
    kind: str,
    gains: dict[str, float],
    name: str,
    rulebase: RuleBase | None = None,
    rulebase_ref: str | None = None,
) -> ControllerSpec:
    """A controller spec running ``exp``'s task (axes, set points, safety limit, engagement)
    with ``gains`` on every force-controlled axis: what ``fuzzkit tune --spec-out`` writes.

    ``correction_m`` is the smaller of ``-u_min`` and ``u_max`` of the gains, ``step_m`` their
    ``rate_limit`` (defaults :data:`DEFAULT_CORRECTION_M`, :data:`DEFAULT_STEP_M`). No sensor
    front end: the simulated loop that found the gains had none.
    """
    bound = min(
        -gains.get("u_min", -DEFAULT_CORRECTION_M), gains.get("u_max", DEFAULT_CORRECTION_M)
    )
    axes = tuple(
        AxisSpec(axis, exp.setpoints[i], gains["kp"], gains["ki"], gains.get("kx"))
        for i, axis in enumerate(AXES)
        if exp.selection[i]
    )
    return ControllerSpec(
        name=name,
        kind=kind,
        period_s=exp.scenario.period_s,
        axes=axes,
        limits=Limits(bound, gains.get("rate_limit", DEFAULT_STEP_M)),
        safety=Safety(
            limit_n=exp.force_limit_n,
            engage_threshold_n=exp.engage_threshold_n,
            engage_samples=exp.engage_samples,
        ),
        rulebase=rulebase if kind == "fuzzy-pi" else None,
        rulebase_ref=rulebase_ref if kind == "fuzzy-pi" else None,
        description=f"{kind} for {exp.name}, gains tuned by fuzzkit tune",
    )
