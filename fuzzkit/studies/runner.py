"""The plant-agnostic closed-loop runner: plant -> F/T (with injected faults) -> controller ->
plant.

Forces and corrections are in the task frame (:mod:`fuzzkit.plants.contract` explains frames
and signs). One :class:`RunResult` holds every series of a run, one sample per period.
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.control.controllers import (
    HybridForceController,
    Surface,
    engine_surface,
    make_axis_controllers,
)
from fuzzkit.errors import ConfigError
from fuzzkit.plants.contract import ContactPlant, PlantSample, Scenario, task_to_base
from fuzzkit.studies.experiments import DEFAULT_GAINS, Experiment
from fuzzkit.studies.plants import make_plant

Vec = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class Faults:
    """Sensor faults injected into the measured force before the controller sees it.

    ``nan_probability``: each sample is NaN with this probability. ``dropout``: ``(start_s,
    length_s)`` during which every sample is missing (NaN). ``spike_probability`` /
    ``spike_n``: a sample gets a random-signed spike of this size on x and z (the plane of the
    experiments). ``delay_steps``: the
    controller sees the sample of ``delay_steps`` periods ago. Seeded, deterministic.
    """

    nan_probability: float = 0.0
    dropout: tuple[float, float] | None = None
    spike_probability: float = 0.0
    spike_n: float = 0.0
    delay_steps: int = 0
    seed: int = 0


def fault_schedule(faults: Faults, periods: int) -> tuple[Vec, npt.NDArray[np.bool_]]:
    """The random part of a fault run, drawn up front: per period, the spike sign (0: none)
    and whether the sample is NaN. Both loops (Python and compiled) inject from this one draw."""
    rng = np.random.default_rng(faults.seed)
    spike = np.zeros(periods)
    nan = np.zeros(periods, dtype=bool)
    for k in range(periods):
        if faults.spike_probability > 0.0 and rng.random() < faults.spike_probability:
            spike[k] = rng.choice([-1.0, 1.0])
        if faults.nan_probability > 0.0 and rng.random() < faults.nan_probability:
            nan[k] = True
    return spike, nan


class _FaultInjector:
    def __init__(self, faults: Faults, periods: int) -> None:
        self.f = faults
        self.spike, self.nan = fault_schedule(faults, periods)
        self.k = 0
        self.queue: list[Vec] = []

    def __call__(self, t_s: float, force: Vec) -> Vec:
        f = self.f
        k = self.k
        self.k += 1
        out = force.copy()
        if self.spike[k] != 0.0:
            out = out + self.spike[k] * f.spike_n * np.array([1.0, 0.0, 1.0])
        if self.nan[k]:
            out = np.full(3, np.nan)
        if f.dropout is not None and f.dropout[0] <= t_s < f.dropout[0] + f.dropout[1]:
            out = np.full(3, np.nan)
        if f.delay_steps > 0:
            self.queue.append(out)
            if len(self.queue) <= f.delay_steps:
                return np.full(3, np.nan)
            return self.queue.pop(0)
        return out


@dataclass(slots=True)
class RunResult:
    """Everything a run produced: time series (one row per controller period) and a summary."""

    experiment: Experiment
    controller: str
    plant: str
    t: Vec
    force: Vec  # measured, task frame (n, 3), NaN where no sample reached the controller
    force_true: Vec  # (n, 3)
    setpoint: Vec  # (n, 3)
    e: Vec
    de: Vec
    du: Vec
    u: Vec  # task-frame correction S*u (+ back-off), (n, 3)
    tool_position: Vec  # base frame (n, 3)
    nominal_position: Vec
    joint_angles: Vec
    in_contact: npt.NDArray[np.bool_]  # any object touches the tool
    # normal contact force per task axis (n, 3), friction excluded (PlantSample.force_normal);
    # NaN rows when the plant does not report it
    force_normal: Vec
    moving: npt.NDArray[np.bool_]  # the nominal path was moving during that period
    arm_points: list[Vec]
    contact_points: list[Vec]
    faults: int
    tripped: bool
    trip_time_s: float | None
    engaged_time_s: float | None
    wall_time_s: float
    messages: dict[str, int] = field(default_factory=dict)
    #: which loop ran: "python" (this module) or "compiled" (fuzzkit.studies.compiled)
    loop: str = "python"
    #: CPU time of the loop alone (s, time.process_time), start-up excluded
    cpu_time_s: float = 0.0
    #: which controller implementation ran (exact engine, lookup table, generated C ...)
    controller_impl: str = ""

    @property
    def real_time_factor(self) -> float:
        """Simulated seconds per CPU second of the loop."""
        return self.sim_time_s / self.cpu_time_s if self.cpu_time_s > 0.0 else math.inf

    @property
    def sim_time_s(self) -> float:
        """Simulated time covered by the run (s)."""
        return float(self.t[-1]) if len(self.t) else 0.0


def load_surface(rulebase: str = "macvicar_whelan") -> Surface:
    """The control surface of a rule base (shipped name or YAML path), by the exact engine."""
    from fuzzkit.formats.registry import load
    from fuzzkit.fuzzy.inference import Engine

    rb = load(rulebase)
    return engine_surface(Engine(rb))


def build_controller(
    exp: Experiment,
    kind: str,
    gains: Mapping[str, float] | None = None,
    surface: Surface | None = None,
) -> HybridForceController:
    """The hybrid force controller of ``exp`` with ``kind`` (pi | fuzzy-pi) axis controllers."""
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
    )


def run(
    exp: Experiment,
    plant: ContactPlant | str = "planar",
    controller: str = "pi",
    *,
    gains: Mapping[str, float] | None = None,
    surface: Surface | None = None,
    hybrid: HybridForceController | None = None,
    seed: int = 0,
    faults: Faults | None = None,
    duration_s: float | None = None,
    latency: tuple[int, int] = (0, 0),
    controller_impl: str = "",
) -> RunResult:
    """Run ``exp`` in closed loop on ``plant`` and record every period.

    ``controller`` is ``pi`` or ``fuzzy-pi`` (the latter needs ``surface``, see
    :func:`load_surface`); a ready ``hybrid`` controller overrides both. ``latency`` is
    ``(sensor_delay, command_delay)`` in periods: per period the plant steps with the
    correction computed ``command_delay`` periods ago (zeros before), its measured force
    (after fault injection) reaches the controller ``sensor_delay`` periods later (the reset
    sample's force before). ``controller_impl`` is only a label for the result.
    """
    sensor_delay, command_delay = check_latency(latency)
    if isinstance(plant, str):
        plant = make_plant(plant)
    ctrl = hybrid or build_controller(exp, controller, gains, surface)
    scn = exp.scenario
    n = round((duration_s or scn.duration_s) / scn.period_s)
    inject = _FaultInjector(faults, n) if faults is not None else None
    period = scn.period_s

    records: list[tuple[Any, ...]] = []
    arm_points: list[Vec] = []
    contact_points: list[Vec] = []
    messages: dict[str, int] = {}
    engaged_at: float | None = None
    path_t = 0.0
    correction_task = np.zeros(3)
    sample: PlantSample = plant.reset(scn, seed=seed)
    sensor_queue = deque([sample.force] * sensor_delay)
    command_queue = deque([np.zeros(3)] * command_delay)
    applied = np.zeros(3)
    wall0 = time.perf_counter()
    cpu0 = time.process_time()
    for _ in range(n):
        held = ctrl.tripped or (
            exp.hold_path_on_contact and ctrl.engaged and engaged_at is not None
        )
        path_before = path_t
        if not held:
            path_t += period
        sample = plant.step(task_to_base(scn, applied), path_t)
        measured = sample.force if inject is None else inject(sample.t_s, sample.force)
        sensor_queue.append(measured)
        correction_task = ctrl.step(sensor_queue.popleft())
        command_queue.append(correction_task)
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
                sample.force_true,
                ctrl.setpoints,
                ctrl.e.copy(),
                ctrl.de.copy(),
                ctrl.du.copy(),
                correction_task.copy(),
                sample.tool_position,
                sample.nominal_position,
                sample.joint_angles,
                sample.in_contact,
                _NO_NORMAL if sample.force_normal is None else sample.force_normal,
                moving,
            )
        )
        arm_points.append(sample.arm_points)
        contact_points.append(sample.contact_points)
    wall = time.perf_counter() - wall0
    cpu = time.process_time() - cpu0
    columns = list(zip(*records, strict=True)) if records else [() for _ in _SERIES]
    arr = {k: np.asarray(v) for k, v in zip(_SERIES, columns, strict=True)}
    return RunResult(
        experiment=exp,
        controller=controller if hybrid is None else "custom",
        plant=plant.name,
        t=arr["t"].astype(np.float64),
        force=arr["force"].astype(np.float64),
        force_true=arr["force_true"].astype(np.float64),
        setpoint=arr["setpoint"].astype(np.float64),
        e=arr["e"].astype(np.float64),
        de=arr["de"].astype(np.float64),
        du=arr["du"].astype(np.float64),
        u=arr["u"].astype(np.float64),
        tool_position=arr["tool_position"].astype(np.float64),
        nominal_position=arr["nominal_position"].astype(np.float64),
        joint_angles=arr["joint_angles"].astype(np.float64),
        in_contact=arr["in_contact"].astype(bool),
        force_normal=arr["force_normal"].astype(np.float64).reshape(-1, 3),
        moving=arr["moving"].astype(bool),
        arm_points=arm_points,
        contact_points=contact_points,
        faults=ctrl.faults,
        tripped=ctrl.tripped,
        trip_time_s=ctrl.trip_time_s,
        engaged_time_s=engaged_at,
        wall_time_s=wall,
        messages=messages,
        loop="python",
        cpu_time_s=cpu,
        controller_impl=controller_impl or _impl_label(controller, hybrid, surface),
    )


def check_latency(latency: tuple[int, int]) -> tuple[int, int]:
    """``(sensor_delay, command_delay)`` as non-negative integers, or a ConfigError."""
    if len(latency) != 2 or any(isinstance(v, bool) or int(v) != v or v < 0 for v in latency):
        raise ConfigError(
            f"latency must be (sensor_delay, command_delay), integers >= 0 (got {latency!r})"
        )
    return int(latency[0]), int(latency[1])


def _impl_label(
    controller: str, hybrid: HybridForceController | None, surface: Surface | None
) -> str:
    if hybrid is not None:
        return "custom"
    if controller == "pi":
        return "pi (python)"
    return f"fuzzy-pi surface {getattr(surface, '__name__', 'callable')} (python)"


_SERIES = (
    "t",
    "force",
    "force_true",
    "setpoint",
    "e",
    "de",
    "du",
    "u",
    "tool_position",
    "nominal_position",
    "joint_angles",
    "in_contact",
    "force_normal",
    "moving",
)

_NO_NORMAL = np.full(3, np.nan)


def _path_moving(scn: Scenario, t0: float, t1: float) -> bool:
    """True when the nominal path changes position between path times t0 and t1."""
    from fuzzkit.plants.environment import nominal_position

    return bool(
        np.any(np.abs(nominal_position(scn.path, t1) - nominal_position(scn.path, t0)) > 1e-9)
    )
