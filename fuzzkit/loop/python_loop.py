"""The plant-agnostic closed-loop runner: plant -> F/T (with injected faults) -> controller ->
plant.

Forces and corrections are in the task frame (:mod:`fuzzkit.plants.contract` explains frames
and signs). One :class:`RunResult` holds every series of a run, one sample per period.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Mapping
from typing import Any, Protocol

import numpy as np
import numpy.typing as npt

from fuzzkit.control.controllers import (
    HybridForceController,
    Surface,
    make_axis_controllers,
)
from fuzzkit.errors import ConfigError
from fuzzkit.loop.adapter import make_plant
from fuzzkit.loop.faults import FaultInjector, Faults, fault_name
from fuzzkit.loop.result import RunResult
from fuzzkit.loop.task import DEFAULT_GAINS, Experiment
from fuzzkit.loop.timing import run_faults_and_latency
from fuzzkit.plants.contract import ContactPlant, PlantSample, Scenario

Vec = npt.NDArray[np.float64]


class LoopController(Protocol):
    """What the loop drives each period: the reference
    (:class:`~fuzzkit.control.controllers.HybridForceController`) or a spec's generated
    controller (:class:`fuzzkit.loop.generated.GeneratedLoopController`). After each
    call the loop reads ``status``, ``engaged``, ``tripped``, ``faults``, ``trip_time_s``,
    ``setpoints``, ``e``, ``de``, ``du`` and ``controllers`` (the reference's axis
    controllers, which may adapt; none for generated code), and where the controller adapts
    (reference axis controllers with ``adapt``, or a generated controller's ``adaptive``)
    ``gain_scale`` and ``stiffness_n_mm``."""

    def step(self, force: Vec | None, rotation: Vec | None = None) -> Vec: ...

    def wait(self) -> Vec: ...


def load_surface(rulebase: str = "macvicar_whelan") -> Surface:
    """The control surface of a rule base (shipped name or YAML path), by the exact engine: its
    inputs by position (error, change), whatever their names."""
    from fuzzkit.control.loop_rulebase import exact_surface, load_loop_rulebase

    return exact_surface(load_loop_rulebase(rulebase))


def build_controller(
    exp: Experiment,
    kind: str,
    gains: Mapping[str, float] | None = None,
    surface: Surface | None = None,
) -> HybridForceController:
    """The hybrid force controller of ``exp`` with ``kind`` (pi | fuzzy-pi) axis controllers.

    An experiment with a controller spec runs the spec's controller
    (:func:`fuzzkit.control.reference.hybrid_from_spec`; ``kind`` is not used), with the
    ``kp``, ``ki``, ``kx`` of ``gains`` on every axis when given (tuning a spec); ``surface``
    replaces the fuzzy-PI's exact engine when given.
    """
    if exp.controller_spec is not None:
        from fuzzkit.control.reference import hybrid_from_spec
        from fuzzkit.control.spec import with_gains
        from fuzzkit.loop.controller_code import spec_surface

        spec = exp.controller_spec
        if surface is None and spec.kind == "fuzzy-pi":
            surface = spec_surface(spec)
        return hybrid_from_spec(with_gains(spec, gains or {}), surface)
    if kind not in DEFAULT_GAINS:
        raise ConfigError(f"unknown controller {kind!r} (expected pi or fuzzy-pi)")
    g = dict(DEFAULT_GAINS[kind])
    g.update(gains or {})
    axes = make_axis_controllers(kind, exp.selection, g, surface)
    return HybridForceController(
        axes,
        exp.setpoints,
        period_s=exp.scenario.period_s,
        force_limit_n=exp.force_limit_n,
        engage_threshold_n=exp.engage_threshold_n,
        engage_samples=exp.engage_samples,
    )


def run(
    exp: Experiment,
    plant: ContactPlant | str = "planar",
    controller: str = "pi",
    *,
    gains: Mapping[str, float] | None = None,
    surface: Surface | None = None,
    hybrid: LoopController | None = None,
    seed: int = 0,
    faults: Faults | None = None,
    duration_s: float | None = None,
    latency: tuple[int, int] | None = None,
    controller_impl: str = "",
) -> RunResult:
    """Run ``exp`` in closed loop on ``plant`` and record every period.

    ``controller`` is ``pi`` or ``fuzzy-pi`` (the latter needs ``surface``, see
    :func:`load_surface`); a ready ``hybrid`` controller overrides both. ``faults``: the
    injected sensor faults (default: the experiment's, seeded by ``seed``). ``latency``:
    ``(sensor, command)`` delays in periods (default: the experiment's).

    Timing of period k: the plant moves with the correction it receives, its measured force
    passes the fault injection into the sensor queue, the controller consumes the sample of
    ``sensor`` periods ago (the queue starts filled with the reset sample's force: when that is no
    measurement, those start-up periods wait, uncounted as sensor faults), and its
    correction enters the command queue, whose output (``command`` periods old; zeros at the
    start) the plant receives in period k + 1. ``controller_impl`` is only a label for the
    result.
    """
    if isinstance(plant, str):
        plant = make_plant(plant)
    ctrl: Any = hybrid or build_controller(exp, controller, gains, surface)
    scn = exp.scenario
    faults, sensor_delay, command_delay = run_faults_and_latency(exp, seed, faults, latency)
    inject = FaultInjector(faults)
    n = round((duration_s or scn.duration_s) / scn.period_s)
    period = scn.period_s

    records: list[tuple[Any, ...]] = []
    arm_points: list[Vec] = []
    contact_points: list[Vec] = []
    statuses: list[int] = []
    messages: dict[str, int] = {}
    engaged_at: float | None = None
    path_t = 0.0
    correction_task = np.zeros(3)
    applied = np.zeros(3)
    sample: PlantSample = plant.reset(scn, seed=seed)
    # (force, tool rotation) pairs: the rotation travels with its sample
    sensor_queue: deque[tuple[Vec, Vec]] = deque(
        (sample.force.copy(), _rotation(scn, sample)) for _ in range(sensor_delay)
    )
    command_queue: deque[Vec] = deque(np.zeros(3) for _ in range(command_delay))
    adaptive = getattr(ctrl, "adaptive", False) or any(
        getattr(c, "adapt", None) is not None for c in ctrl.controllers
    )
    scales: list[Vec] = []
    estimates: list[Vec] = []
    wall0 = time.perf_counter()
    cpu0 = time.process_time()
    controlled = np.asarray(exp.selection, dtype=bool)
    for k in range(n):
        held = ctrl.tripped or (
            exp.hold_path_on_contact and ctrl.engaged and engaged_at is not None
        )
        path_before = path_t
        if not held:
            path_t += period
        sample = plant.step(applied, path_t)
        delivered = inject(sample.t_s, sample.force)
        sensor_queue.append((delivered, _rotation(scn, sample)))
        measured, rotation = sensor_queue.popleft()
        if k < sensor_delay and not np.all(np.isfinite(measured[controlled])):
            correction_task = ctrl.wait()  # start-up: no measurement can have arrived yet
        else:
            correction_task = ctrl.step(measured, rotation)
        # the correction is along the controller's (the sensor's) axes at that sample
        command_queue.append(rotation @ correction_task)
        applied = command_queue.popleft()
        if ctrl.engaged and engaged_at is None:
            engaged_at = sample.t_s
        for m in sample.messages:
            messages[m] = messages.get(m, 0) + 1
        moving = path_t > path_before and _path_moving(scn, path_before, path_t)
        # one tuple per period, in _SERIES order; transposed once after the loop
        records.append(
            (
                sample.t_s,
                measured,
                delivered,
                sample.force_true,
                ctrl.setpoints,
                ctrl.e.copy(),
                ctrl.de.copy(),
                ctrl.du.copy(),
                correction_task.copy(),
                sample.tool_position,
                sample.nominal_position,
                sample.target_position,
                sample.joint_angles,
                sample.in_contact,
                _NO_NORMAL if sample.force_normal is None else sample.force_normal,
                moving,
                rotation.reshape(9),
            )
        )
        if adaptive:
            scales.append(ctrl.gain_scale)
            estimates.append(ctrl.stiffness_n_mm)
        arm_points.append(sample.arm_points)
        statuses.append(ctrl.status)
        contact_points.append(sample.contact_points)
    wall = time.perf_counter() - wall0
    cpu = time.process_time() - cpu0
    columns = list(zip(*records, strict=True)) if records else [() for _ in _SERIES]
    arr = {k: np.asarray(v) for k, v in zip(_SERIES, columns, strict=True)}
    return RunResult(
        experiment=exp,
        controller=_controller_name(exp, controller, hybrid),
        plant=plant.name,
        t=arr["t"].astype(np.float64),
        force=arr["force"].astype(np.float64),
        force_sensor=arr["force_sensor"].astype(np.float64),
        force_true=arr["force_true"].astype(np.float64),
        setpoint=arr["setpoint"].astype(np.float64),
        e=arr["e"].astype(np.float64),
        de=arr["de"].astype(np.float64),
        du=arr["du"].astype(np.float64),
        u=arr["u"].astype(np.float64),
        tool_position=arr["tool_position"].astype(np.float64),
        nominal_position=arr["nominal_position"].astype(np.float64),
        target_position=arr["target_position"].astype(np.float64),
        joint_angles=arr["joint_angles"].astype(np.float64),
        in_contact=arr["in_contact"].astype(bool),
        force_normal=arr["force_normal"].astype(np.float64).reshape(-1, 3),
        moving=arr["moving"].astype(bool),
        arm_points=arm_points,
        contact_points=contact_points,
        faults=ctrl.faults,
        tripped=ctrl.tripped,
        seed=seed,
        latency_periods=(sensor_delay, command_delay),
        fault=fault_name(faults),
        fault_seed=faults.seed,
        trip_time_s=ctrl.trip_time_s,
        engaged_time_s=engaged_at,
        wall_time_s=wall,
        messages=messages,
        loop="python",
        cpu_time_s=cpu,
        controller_impl=controller_impl or _impl_label(exp, controller, hybrid, surface),
        gain_scale=np.array(scales).reshape(-1, 3) if adaptive else None,
        stiffness_n_mm=np.array(estimates).reshape(-1, 3) if adaptive else None,
        status=np.asarray(statuses, dtype=np.int64),
        rotation=arr["rotation"].astype(np.float64).reshape(-1, 9),
    )


def _rotation(scn: Scenario, sample: PlantSample) -> Vec:
    """World-from-sensor rotation of a sample: the plant's, else the scenario's task frame."""
    return scn.rotation if sample.tool_rotation is None else sample.tool_rotation


def _controller_name(exp: Experiment, controller: str, hybrid: object) -> str:
    if hybrid is not None:
        return str(getattr(hybrid, "kind", "custom"))  # a generated controller knows its kind
    return controller if exp.controller_spec is None else exp.controller_spec.kind


def _impl_label(
    exp: Experiment,
    controller: str,
    hybrid: LoopController | None,
    surface: Surface | None,
) -> str:
    if hybrid is not None:  # a generated controller names its code
        label = getattr(hybrid, "label", None)
        return "custom" if label is None else f"{label} (python loop)"
    if exp.controller_spec is not None:
        spec = exp.controller_spec
        on = spec.rulebase.name if spec.rulebase is not None else ""
        return f"spec {spec.name} ({spec.kind}{' ' + on if on else ''}, python)"
    if controller == "pi":
        return "pi (python)"
    return f"fuzzy-pi surface {getattr(surface, '__name__', 'callable')} (python)"


_SERIES = (
    "t",
    "force",
    "force_sensor",
    "force_true",
    "setpoint",
    "e",
    "de",
    "du",
    "u",
    "tool_position",
    "nominal_position",
    "target_position",
    "joint_angles",
    "in_contact",
    "force_normal",
    "moving",
    "rotation",
)

_NO_NORMAL = np.full(3, np.nan)


def _path_moving(scn: Scenario, t0: float, t1: float) -> bool:
    """True when the nominal path changes position between path times t0 and t1."""
    from fuzzkit.plants.environment import nominal_position

    return bool(
        np.any(np.abs(nominal_position(scn.path, t1) - nominal_position(scn.path, t0)) > 1e-9)
    )
