"""What every compiled loop shares outside numba: the controller's arguments (around the
generated controller), the warm-up, and turning the recording arrays into the runner's
:class:`RunResult`."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.loop.compiled import period as P
from fuzzkit.loop.compiled.generated_controller import GeneratedController
from fuzzkit.loop.faults import Faults, fault_name, fault_schedule
from fuzzkit.loop.result import RunResult
from fuzzkit.loop.task import Experiment
from fuzzkit.loop.timing import run_faults_and_latency

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]


@dataclass(slots=True)
class ControllerArgs:
    """The controller half of a compiled run's arguments (plant-independent): the loop's
    parameter vector, the task, the generated controller and its state, the fault schedule."""

    cp: FloatArray
    selection: FloatArray
    setpoints: FloatArray
    #: the generated controller's NAME_controller_step (ctypes) and its NAME_controller_t
    c_step: Any
    c_state: FloatArray
    spike: FloatArray
    nan: BoolArray
    impl: str
    faults: Faults
    latency: tuple[int, int]
    periods: int
    #: the controller's kind (pi, fuzzy-pi), as the run result names it
    kind: str

    def record(self) -> tuple[Any, ...]:
        """The controller's arrays as the compiled loops take them: ``(cp, selection,
        setpoints, c_state, spike, nan)``."""
        return (self.cp, self.selection, self.setpoints, self.c_state, self.spike, self.nan)


def controller_args(
    exp: Experiment,
    generated: GeneratedController,
    seed: int,
    faults: Faults | None,
    duration_s: float | None,
    latency: tuple[int, int] | None,
) -> ControllerArgs:
    """The compiled run's arguments around ``generated``, the run's controller: its spec's
    axes, set points and engagement; the run's latency and fault schedule as ``runner.run``
    sets them up. The loop's parameter vector carries only what the loop itself does (period,
    delays, faults, path hold, the initial engagement); the controller's settings are the
    generated code's."""
    from dataclasses import replace

    from fuzzkit.loop.task import with_spec

    spec = generated.spec
    task = replace(with_spec(exp, spec), controller_spec=None)
    faults, sensor_delay, command_delay = run_faults_and_latency(task, seed, faults, latency)
    scn = task.scenario
    n = round((duration_s or scn.duration_s) / scn.period_s)
    spike, nan = fault_schedule(faults, n)
    cp = np.zeros(P.N_CP)
    thr = spec.safety.engage_threshold_n
    cp[P.C_ENGAGE_THR] = math.nan if thr is None else thr
    cp[P.C_HOLD] = 1.0 if task.hold_path_on_contact else 0.0
    cp[P.C_PERIOD] = scn.period_s
    cp[P.C_SENSOR_DELAY] = sensor_delay
    cp[P.C_COMMAND_DELAY] = command_delay
    cp[P.C_DROPOUT_START] = math.nan if faults.dropout is None else faults.dropout[0]
    cp[P.C_DROPOUT_LENGTH] = 0.0 if faults.dropout is None else faults.dropout[1]
    cp[P.C_SPIKE_N] = faults.spike_n
    off = faults.offset
    cp[P.C_OFFSET_START] = math.nan if off is None else off[0]
    cp[P.C_OFFSET_LENGTH] = 0.0 if off is None else off[1]
    cp[P.C_OFFSET_N] = 0.0 if off is None else off[2]
    return ControllerArgs(
        cp=cp,
        selection=np.array([1.0 if s else 0.0 for s in task.selection]),
        setpoints=np.asarray(task.setpoints, dtype=np.float64),
        c_step=generated.step_function,
        c_state=generated.fresh_state(),
        spike=spike,
        nan=nan,
        impl=generated.label + " (compiled loop)",
        faults=faults,
        latency=(sensor_delay, command_delay),
        periods=n,
        kind=spec.kind,
    )


def recording(n: int, joints: int, arm_points: int, n_obj: int, **own: Any) -> dict[str, Any]:
    """The recording arrays of an ``n``-period compiled run, in the order every plant's loop
    takes them (``r_t`` ...), then the plant's ``own`` (its loop's last arguments before
    ``out_scalars``): ``joints`` joint angles, ``arm_points`` points of the drawn arm,
    ``n_obj`` contact points at most."""
    return {
        "t": np.empty(n),
        "force": np.empty((n, 3)),
        "force_sensor": np.empty((n, 3)),
        "force_true": np.empty((n, 3)),
        "e": np.empty((n, 3)),
        "de": np.empty((n, 3)),
        "du": np.empty((n, 3)),
        "u": np.empty((n, 3)),
        "tool": np.empty((n, 3)),
        "nominal": np.empty((n, 3)),
        "target": np.empty((n, 3)),
        "joints": np.empty((n, joints)),
        "contact": np.empty(n, dtype=np.bool_),
        "force_normal": np.empty((n, 3)),
        "moving": np.empty(n, dtype=np.bool_),
        "arm": np.empty((n, arm_points, 3)),
        "points": np.zeros((n, max(n_obj, 1), 3)),
        "npoints": np.empty(n, dtype=np.int64),
        "status": np.empty(n, dtype=np.int64),
        **own,
    }


def result_from_recording(
    exp: Experiment,
    plant: str,
    ctrl: ControllerArgs,
    seed: int,
    rec: dict[str, Any],
    scalars: FloatArray,
    messages: dict[str, int],
    cpu: float,
    wall: float,
) -> RunResult:
    """The :class:`RunResult` of a compiled run's recording arrays (any plant)."""
    n = rec["t"].shape[0]
    trip_time = float(scalars[P.R_TRIP_TIME])
    engaged_time = float(scalars[P.R_ENGAGED_TIME])
    return RunResult(
        experiment=exp,
        controller=ctrl.kind,
        plant=plant,
        t=rec["t"],
        force=rec["force"],
        force_sensor=rec["force_sensor"],
        force_true=rec["force_true"],
        setpoint=np.tile(ctrl.setpoints, (n, 1)),
        e=rec["e"],
        de=rec["de"],
        du=rec["du"],
        u=rec["u"],
        tool_position=rec["tool"],
        nominal_position=rec["nominal"],
        target_position=rec["target"],
        joint_angles=rec["joints"],
        in_contact=rec["contact"],
        force_normal=rec["force_normal"],
        moving=rec["moving"],
        arm_points=list(rec["arm"]),
        contact_points=[rec["points"][k, : rec["npoints"][k]] for k in range(n)],
        faults=int(scalars[P.R_FAULTS]),
        tripped=bool(scalars[P.R_TRIPPED]),
        seed=seed,
        latency_periods=ctrl.latency,
        fault=fault_name(ctrl.faults),
        fault_seed=ctrl.faults.seed,
        trip_time_s=None if math.isnan(trip_time) else trip_time,
        engaged_time_s=None if math.isnan(engaged_time) else engaged_time,
        wall_time_s=wall,
        messages=messages,
        loop="compiled",
        cpu_time_s=cpu,
        controller_impl=ctrl.impl,
        status=rec["status"],
        # the compiled plants never turn the tool: the scenario's task frame, every period
        rotation=np.tile(np.asarray(exp.scenario.rotation, dtype=np.float64).reshape(9), (n, 1)),
    )


#: Kernels already loaded in this process, by name.
_WARMED: set[str] = set()


def warm_up(
    kernel: Callable[..., Any],
    plant: tuple[Any, ...],
    noise: Any,
    reset_force: Any,
    ctrl: ControllerArgs,
    rec: dict[str, Any],
    scalars: Any,
    extra: tuple[Any, ...] = (),
) -> None:
    """Run ``kernel`` over zero periods once per process, with the run's argument types
    (``extra``: a plant's own arguments after the reset force, as :func:`run_kernel`'s).

    The first call loads the machine code from numba's on-disk cache (or compiles it after an
    install); done here, that start-up cost stays out of the loop's CPU time. Zero periods
    never call the controller, so its state is untouched.
    """
    key = getattr(kernel, "__name__", repr(kernel))
    if key in _WARMED:
        return
    own = tuple(np.array(x, copy=True) if isinstance(x, np.ndarray) else x for x in plant)
    empty = tuple(v[:0] for v in rec.values())
    kernel(own, noise, reset_force, *extra, ctrl.record(), ctrl.c_step, empty, scalars.copy())
    _WARMED.add(key)


def fields_record(arrays: Any) -> tuple[Any, ...]:
    """A plant's packed arrays (a dataclass: ``Arm6Arrays``, ``PlanarArrays``) as the record its
    compiled loop takes: the fields in declaration order, the arrays themselves (not copies:
    the loop updates the plant's state in place)."""
    from dataclasses import fields

    return tuple(getattr(arrays, f.name) for f in fields(arrays))


def run_kernel(
    kernel: Callable[..., Any],
    plant: tuple[Any, ...],
    noise: Any,
    reset_force: Any,
    ctrl: ControllerArgs,
    rec: dict[str, Any],
    scalars: Any,
    extra: tuple[Any, ...] = (),
) -> tuple[Any, float, float]:
    """One compiled run: ``kernel`` on its named records (warmed first, :func:`warm_up`);
    returns what it returned, and the CPU and wall seconds of the call alone. ``extra``: the
    plant's own arguments after the reset force (MuJoCo's ``MjData`` views and C helpers)."""
    import time

    warm_up(kernel, plant, noise, reset_force, ctrl, rec, scalars, extra)
    wall0 = time.perf_counter()
    cpu0 = time.process_time()
    done = kernel(
        plant, noise, reset_force, *extra, ctrl.record(), ctrl.c_step, tuple(rec.values()),
        scalars,
    )  # fmt: skip
    return done, time.process_time() - cpu0, time.perf_counter() - wall0
