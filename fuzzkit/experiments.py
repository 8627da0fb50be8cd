"""The paper's three experiments, a plant-agnostic closed-loop runner, and force-control metrics.

* E1: a cup carried along a nominal path meets an unexpected hammer lying on the table; on
  contact the force loop takes over (the path is held) and keeps 10 N along z, 0 N along x.
* E2: a straight path over a rough, slightly tilted and offset workpiece keeping 30 N along z.
* E3: the tool slides along the rough floor of a workpiece towards a side wall it does not know
  precisely, keeping 30 N along z and 6 N along x (pressing into the wall once it reaches it).

The runner drives any ``fuzzkit.plant.ContactPlant``; forces and corrections are in the task
frame (``fuzzkit.plant`` explains frames and signs). Metrics are computed on the *true* contact
force, so the sensor noise is not counted as control error.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.control import (
    HybridForceController,
    Surface,
    engine_surface,
    make_axis_controllers,
)
from fuzzkit.errors import ConfigError
from fuzzkit.plant import (
    Box,
    ContactModel,
    ContactPlant,
    PlantSample,
    RoughSurface,
    Scenario,
    SensorModel,
    Table,
    ToolModel,
    Waypoint,
    make_plant,
    task_to_base,
)

Vec = npt.NDArray[np.float64]

AXES = ("x", "y", "z")

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


def _e1() -> Experiment:
    table_z = -0.30
    cup = ToolModel(length_m=0.14, radius_m=0.035, name="cup")
    # The hammer lies on the table where the CAD cell has nothing: 4 cm high.
    hammer = Box(center_x=0.47, center_z=table_z + 0.02, size_x=0.12, size_z=0.04, name="hammer")
    place = (0.52, table_z + cup.radius_m)  # the nominal place pose: cup on the bare table
    start = (0.40, -0.19)
    dist = math.hypot(place[0] - start[0], place[1] - start[1])
    t_end = 0.2 + dist / 0.04  # 40 mm/s approach
    scn = Scenario(
        name="E1",
        description="cup carried towards the table meets an unexpected hammer",
        path=(
            Waypoint(0.0, start[0], 0.0, start[1]),
            Waypoint(0.2, start[0], 0.0, start[1]),
            Waypoint(t_end, place[0], 0.0, place[1]),
        ),
        objects=(Table(table_z), hammer),
        duration_s=5.0,
        contact=ContactModel(stiffness_n_per_m=1.0e4, damping_n_s_per_m=50.0, friction=0.4),
        sensor=SensorModel(rate_hz=250.0, noise_std_n=0.1),
        tool=cup,
    )
    return Experiment(
        name="E1",
        title="cup meets an unexpected hammer: 10 N along z, 0 N along x",
        scenario=scn,
        setpoints=(0.0, 0.0, 10.0),
        selection=(True, False, True),
        force_limit_n=25.0,
        engage_threshold_n=1.0,
        hold_path_on_contact=True,
        steady_window_s=1.0,
    )


def _workpiece(seed: int, x_max: float = 0.70) -> RoughSurface:
    # CAD says the top is flat at z = -0.30; really it is 1 mm higher and tilted down by 0.8 deg.
    return RoughSurface(
        x_min=0.30,
        x_max=x_max,
        height_m=-0.30,
        offset_m=0.001,
        tilt_rad=math.radians(-0.8),
        roughness_rms_m=0.0002,
        seed=seed,
        name="workpiece",
    )


def _e2() -> Experiment:
    # Tip height 2 mm into the CAD surface (20 mm probe): the usual programmed interference that
    # makes sure the tool finds a surface whose height is only roughly known.
    touch_z = -0.30 + 0.02 - 0.002
    path = (
        Waypoint(0.0, 0.35, 0.0, touch_z + 0.022),
        Waypoint(1.1, 0.35, 0.0, touch_z),  # 20 mm/s approach
        Waypoint(1.5, 0.35, 0.0, touch_z),
        Waypoint(1.5 + 0.25 / 0.025, 0.60, 0.0, touch_z),  # 25 mm/s along x
    )
    scn = Scenario(
        name="E2",
        description="straight path over a rough, tilted workpiece",
        path=path,
        objects=(_workpiece(seed=2),),
        duration_s=path[-1].t_s + 1.0,
        contact=ContactModel(stiffness_n_per_m=1.0e4, damping_n_s_per_m=50.0, friction=0.3),
    )
    return Experiment(
        name="E2",
        title="straight path on a rough workpiece: 30 N along z",
        scenario=scn,
        setpoints=(0.0, 0.0, 30.0),
        selection=(False, False, True),
        force_limit_n=60.0,
        engage_threshold_n=1.0,
        steady_window_s=1.0,
    )


def _e3() -> Experiment:
    touch_z = -0.30 + 0.02 - 0.002
    wall_x = 0.545  # CAD says 0.55: the wall is 5 mm closer than programmed
    path = (
        Waypoint(0.0, 0.44, 0.0, touch_z + 0.022),
        Waypoint(1.1, 0.44, 0.0, touch_z),
        Waypoint(1.5, 0.44, 0.0, touch_z),
        Waypoint(1.5 + 0.09 / 0.025, 0.53, 0.0, touch_z),  # slide towards the CAD corner
    )
    wall = Box(center_x=wall_x + 0.025, center_z=-0.25, size_x=0.05, size_z=0.12, name="wall")
    scn = Scenario(
        name="E3",
        description="slide along a rough floor into a side wall",
        path=path,
        objects=(_workpiece(seed=3, x_max=wall_x + 0.05), wall),
        duration_s=path[-1].t_s + 2.0,
        contact=ContactModel(stiffness_n_per_m=1.0e4, damping_n_s_per_m=50.0, friction=0.15),
    )
    return Experiment(
        name="E3",
        title="floor and wall: 6 N along x, 30 N along z",
        scenario=scn,
        setpoints=(6.0, 0.0, 30.0),
        selection=(True, False, True),
        force_limit_n=60.0,
        engage_threshold_n=1.0,
        steady_window_s=1.0,
    )


EXPERIMENTS = {"E1": _e1, "E2": _e2, "E3": _e3}


def experiment(name: str) -> Experiment:
    """The experiment called ``name`` (E1, E2, E3; case-insensitive)."""
    factory = EXPERIMENTS.get(name.upper())
    if factory is None:
        raise ConfigError(f"unknown experiment {name!r} (expected one of {', '.join(EXPERIMENTS)})")
    return factory()


def with_stiffness(exp: Experiment, stiffness_n_per_m: float) -> Experiment:
    """The same experiment in an environment of another contact stiffness."""
    scn = exp.scenario
    return replace(
        exp,
        scenario=replace(scn, contact=replace(scn.contact, stiffness_n_per_m=stiffness_n_per_m)),
    )


def press_experiment(stiffness_n_per_m: float, gap_m: float = 0.0002) -> Experiment:
    """E1's hammer, approached under force control from ``gap_m`` above it (path held).

    Isolates the force loop's stability from the impact of a moving approach: used for the
    stiffness study (10, 100, 1000 N/mm), where the approach speed is what the controller
    commands for a 10 N error.
    """
    e1 = _e1()
    hammer = next(o for o in e1.scenario.objects if isinstance(o, Box))
    top = hammer.center_z + 0.5 * hammer.size_z
    x = hammer.center_x
    z = top + e1.scenario.tool.radius_m + gap_m
    scn = replace(
        e1.scenario,
        name="press",
        description="press on the hammer from just above it",
        path=(Waypoint(0.0, x, 0.0, z),),
        duration_s=3.0,
        contact=replace(e1.scenario.contact, stiffness_n_per_m=stiffness_n_per_m),
    )
    return replace(
        e1,
        name="press",
        title="press 10 N on the hammer",
        scenario=scn,
        engage_threshold_n=None,
        hold_path_on_contact=False,
    )


def scaled_gains(kind: str, stiffness_n_per_m: float) -> dict[str, float]:
    """Default gains scaled for another contact stiffness (same loop gain ``Ki*k`` per step).

    The loop gain of the incremental force loop is ``Ki * k`` per period; the defaults are tuned
    for ``k = 10 N/mm``, so the correction gains are scaled by ``1e4 / k`` (``kx`` for fuzzy-PI).
    """
    g = dict(DEFAULT_GAINS[kind])
    factor = 1.0e4 / stiffness_n_per_m
    for key in ("kp", "ki") if kind == "pi" else ("kx",):
        g[key] *= factor
    return g


# --------------------------------------------------------------------------------------------
# Sensor faults (injected between the plant and the controller)
# --------------------------------------------------------------------------------------------


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


class _FaultInjector:
    def __init__(self, faults: Faults) -> None:
        self.f = faults
        self.rng = np.random.default_rng(faults.seed)
        self.queue: list[Vec] = []

    def __call__(self, t_s: float, force: Vec) -> Vec:
        f = self.f
        out = force.copy()
        if f.spike_probability > 0.0 and self.rng.random() < f.spike_probability:
            out = out + self.rng.choice([-1.0, 1.0]) * f.spike_n * np.array([1.0, 0.0, 1.0])
        if f.nan_probability > 0.0 and self.rng.random() < f.nan_probability:
            out = np.full(3, np.nan)
        if f.dropout is not None and f.dropout[0] <= t_s < f.dropout[0] + f.dropout[1]:
            out = np.full(3, np.nan)
        if f.delay_steps > 0:
            self.queue.append(out)
            if len(self.queue) <= f.delay_steps:
                return np.full(3, np.nan)
            return self.queue.pop(0)
        return out


# --------------------------------------------------------------------------------------------
# Runner
# --------------------------------------------------------------------------------------------


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

    @property
    def sim_time_s(self) -> float:
        """Simulated time covered by the run (s)."""
        return float(self.t[-1]) if len(self.t) else 0.0


def load_surface(rulebase: str = "macvicar_whelan") -> Surface:
    """The control surface of a rule base (shipped name or YAML path), by the exact engine."""
    from fuzzkit.inference import Engine
    from fuzzkit.registry import load

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
) -> RunResult:
    """Run ``exp`` in closed loop on ``plant`` and record every period.

    ``controller`` is ``pi`` or ``fuzzy-pi`` (the latter needs ``surface``, see
    :func:`load_surface`); a ready ``hybrid`` controller overrides both.
    """
    if isinstance(plant, str):
        plant = make_plant(plant)
    ctrl = hybrid or build_controller(exp, controller, gains, surface)
    scn = exp.scenario
    inject = _FaultInjector(faults) if faults is not None else None
    n = round((duration_s or scn.duration_s) / scn.period_s)
    period = scn.period_s

    records: list[tuple[Any, ...]] = []
    arm_points: list[Vec] = []
    contact_points: list[Vec] = []
    messages: dict[str, int] = {}
    engaged_at: float | None = None
    path_t = 0.0
    correction_task = np.zeros(3)
    wall0 = time.perf_counter()
    sample: PlantSample = plant.reset(scn, seed=seed)
    for _ in range(n):
        held = ctrl.tripped or (
            exp.hold_path_on_contact and ctrl.engaged and engaged_at is not None
        )
        path_before = path_t
        if not held:
            path_t += period
        sample = plant.step(task_to_base(scn, correction_task), path_t)
        measured = sample.force if inject is None else inject(sample.t_s, sample.force)
        correction_task = ctrl.step(measured)
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
    )


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
    from fuzzkit.plant import nominal_position

    return bool(
        np.any(np.abs(nominal_position(scn.path, t1) - nominal_position(scn.path, t0)) > 1e-9)
    )


# --------------------------------------------------------------------------------------------
# Metrics
# --------------------------------------------------------------------------------------------


def overshoot_pct(f: Vec, setpoint: float) -> float | None:
    """Peak excursion beyond the set point in the direction of approach, % of ``|setpoint|``.

    ``f`` is the force from the moment of first contact on. None for a zero set point (no
    scale to compare with); 0 when the force never passes the set point.
    """
    if setpoint == 0.0 or len(f) == 0:
        return None
    excess = float(np.max((f - setpoint) * math.copysign(1.0, setpoint)))
    return max(0.0, 100.0 * excess / abs(setpoint))


def settling_time(
    t: Vec, f: Vec, setpoint: float, t0: float, band: float = 0.05, zero_band_n: float = 0.5
) -> float | None:
    """Time from ``t0`` until ``f`` enters and stays in the band around ``setpoint``.

    The band is ``band * |setpoint|`` (5 %) or ``zero_band_n`` newtons for a zero set point.
    None when the final sample is outside the band (never settled).
    """
    tol = band * abs(setpoint) if setpoint != 0.0 else zero_band_n
    mask = t >= t0
    tt, ff = t[mask], f[mask]
    if len(tt) == 0:
        return None
    outside = np.abs(ff - setpoint) > tol
    if outside[-1]:
        return None
    idx = np.nonzero(outside)[0]
    if len(idx) == 0:
        return float(tt[0] - t0)
    return float(tt[idx[-1] + 1] - t0)


def steady_state_error(f: Vec, setpoint: float) -> tuple[float, float]:
    """Mean and standard deviation of the error ``setpoint - f`` over the samples given."""
    if len(f) == 0:
        return (math.nan, math.nan)
    err = setpoint - f
    return (float(np.mean(err)), float(np.std(err)))


def rms(x: Vec) -> float | None:
    """Root mean square of ``x``; None for an empty selection."""
    return float(np.sqrt(np.mean(np.square(x)))) if len(x) else None


#: Normal force (N) that marks an axis's first contact when the experiment has no engage
#: threshold (the force loop active from the start, as in ``press_experiment``).
CONTACT_THRESHOLD_N = 1.0


def axis_contact(result: RunResult, axis: int) -> npt.NDArray[np.bool_] | None:
    """Per sample: does the tool touch a surface that faces task ``axis``?

    True where the normal contact force credited to that axis (``RunResult.force_normal``,
    friction excluded) is positive in the direction of the axis's set point (either direction
    for a 0 N set point). None when the plant does not report normal forces.
    """
    normal = result.force_normal[:, axis]
    if len(normal) == 0 or not np.all(np.isfinite(normal)):
        return None
    sp = float(result.experiment.setpoints[axis])
    pressing = normal * math.copysign(1.0, sp) if sp != 0.0 else np.abs(normal)
    touching: npt.NDArray[np.bool_] = pressing > 0.0
    return touching


def axis_first_contact(result: RunResult, axis: int) -> int | None:
    """Index of task ``axis``'s first contact: its normal force first reaches the threshold.

    The threshold is the experiment's engage threshold (``CONTACT_THRESHOLD_N`` without one),
    applied to the normal contact force credited to the axis in the direction of its set point,
    so friction from sliding on a floor (``mu * f_z`` along x) never counts as an x contact.
    Falls back to the run's first contact with any object when the plant does not report
    normal forces. None when the axis never touches a surface facing it.
    """
    normal = result.force_normal[:, axis]
    if len(normal) == 0 or not np.all(np.isfinite(normal)):
        idx = np.nonzero(result.in_contact)[0]
        return int(idx[0]) if len(idx) else None
    exp = result.experiment
    thr = exp.engage_threshold_n if exp.engage_threshold_n is not None else CONTACT_THRESHOLD_N
    sp = float(exp.setpoints[axis])
    pressing = normal * math.copysign(1.0, sp) if sp != 0.0 else np.abs(normal)
    idx = np.nonzero(pressing >= thr)[0]
    return int(idx[0]) if len(idx) else None


def path_driving(result: RunResult, axis: int) -> npt.NDArray[np.bool_]:
    """Per sample: the nominal path moved along task ``axis`` during that period."""
    nominal_task = result.nominal_position @ result.experiment.scenario.rotation
    driving = np.zeros(len(result.t), dtype=bool)
    if len(driving) > 1:
        driving[1:] = np.abs(np.diff(nominal_task[:, axis])) > 1e-9
    return driving


def axis_metrics(result: RunResult, axis: int) -> dict[str, float | None]:
    """The per-axis figures of a run (keys as in ``fuzzkit simulate --json``).

    Each axis is measured from *its own* first contact (:func:`axis_first_contact`): in E3 the
    tool slides on the floor for seconds before x meets the wall. An axis that never touches a
    surface facing it (E1's x, held at 0 N while the cup rests on the hammer) has
    ``first_contact_s`` None and is measured from the run's first contact with anything, when
    its loop starts holding it.

    * ``overshoot_pct``: peak beyond the set point from the axis's first contact on. Where the
      nominal path keeps driving into the surface after contact, the force follows a ramp
      disturbance and this peak is the loop's ramp-following error (for an incremental PI,
      ``k * v * T / (ki * k)`` newtons: E3's x, 25 mm/s into a 10 N/mm wall, about 10 N).
    * ``settling_time_s``: into the 5 % band (0.5 N for 0 N) and staying there, counted from
      the end of the approach: the axis's first contact or, while the nominal path still moves
      along that axis, the period it stops (a force cannot settle while the path pushes it).
    * ``contact_lost_s``: time after the first contact without touching a surface facing the
      axis.
    """
    exp = result.experiment
    t, f = result.t, result.force_true[:, axis]
    sp = float(exp.setpoints[axis])
    out: dict[str, float | None] = {
        "setpoint": sp,
        "first_contact_s": None,
        "overshoot_pct": None,
        "settling_time_s": None,
        "steady_state_error_mean": None,
        "steady_state_error_std": None,
        "rms_error": None,
        "peak_force": float(np.max(np.abs(f))) if len(f) else None,
        "contact_lost_s": None,
    }
    own = axis_first_contact(result, axis)
    touching = axis_contact(result, axis)
    if own is not None:
        i0 = own
        out["first_contact_s"] = float(t[i0])
    else:
        any_contact = np.nonzero(result.in_contact)[0]
        if len(any_contact) == 0:
            return out
        i0 = int(any_contact[0])
        touching = None  # no surface faces this axis: count contact with anything
    if touching is None:
        touching = result.in_contact
    t0 = float(t[i0])
    out["overshoot_pct"] = overshoot_pct(f[i0:], sp)
    driving = path_driving(result, axis)
    i_settle = i0
    while i_settle < len(t) and driving[i_settle]:
        i_settle += 1
    if i_settle < len(t):
        out["settling_time_s"] = settling_time(t, f, sp, float(t[i_settle]))
    steady = t >= t[-1] - exp.steady_window_s
    mean, std = steady_state_error(f[steady], sp)
    out["steady_state_error_mean"] = mean
    out["steady_state_error_std"] = std
    # While the path moves after the transient of first contact (one settling budget of 0.5 s).
    moving = result.moving & (t >= t0 + 0.5)
    out["rms_error"] = rms(sp - f[moving])
    period = float(exp.scenario.period_s)
    out["contact_lost_s"] = float(np.count_nonzero(~touching[i0:]) * period)
    return out


#: The per-axis keys of the JSON summary (``fuzzkit simulate --json``), in order.
SUMMARY_AXIS_KEYS = (
    "setpoint",
    "first_contact_s",
    "overshoot_pct",
    "settling_time_s",
    "steady_state_error_mean",
    "steady_state_error_std",
    "rms_error",
    "peak_force",
    "contact_lost_s",
)


def summary(result: RunResult) -> dict[str, Any]:
    """The JSON summary of a run: experiment, controller, plant, times, per-axis metrics.

    Only force-controlled axes appear under ``axes`` (z first). Values that do not apply (the
    overshoot of a 0 N set point, the RMS while moving of a held path) are None (JSON null).
    """
    axes: dict[str, dict[str, float | None]] = {}
    for i in (2, 0, 1):
        if result.experiment.selection[i]:
            m = axis_metrics(result, i)
            axes[AXES[i]] = {k: m[k] for k in SUMMARY_AXIS_KEYS}
    return {
        "experiment": result.experiment.name,
        "controller": result.controller,
        "plant": result.plant,
        "sim_time_s": round(result.sim_time_s, 6),
        "wall_time_s": round(result.wall_time_s, 4),
        "axes": axes,
    }
