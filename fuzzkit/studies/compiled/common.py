"""What every compiled loop shares outside numba: the controller's arguments, the warm-up, and
turning the recording arrays into the runner's :class:`RunResult`."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.control.spec import ControllerSpec
from fuzzkit.errors import ConfigError
from fuzzkit.plants.contract import UnsupportedPlant
from fuzzkit.studies.compiled import period as P
from fuzzkit.studies.compiled.generated_c import GeneratedC
from fuzzkit.studies.compiled.generated_controller import GeneratedController
from fuzzkit.studies.compiled.table import table_arrays
from fuzzkit.studies.experiments import DEFAULT_GAINS, Experiment
from fuzzkit.studies.faults import Faults, fault_name, fault_schedule
from fuzzkit.studies.runner import RunResult, build_controller, run_faults_and_latency

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]


@dataclass(slots=True)
class ControllerArgs:
    """The controller half of a compiled run's arguments (plant-independent)."""

    cp: FloatArray
    selection: FloatArray
    setpoints: FloatArray
    table: tuple[FloatArray, FloatArray, FloatArray, IntArray]
    c_eval: Any  # None, or the generated C's NAME_eval (ctypes) that replaces the table
    #: None, or the generated controller's NAME_controller_step (ctypes) that replaces the
    #: loop's controller, and its fresh NAME_controller_t
    c_step: Any
    c_state: FloatArray
    spike: FloatArray
    nan: BoolArray
    impl: str
    faults: Faults
    latency: tuple[int, int]
    periods: int


def controller_args(
    exp: Experiment,
    controller: str,
    gains: Mapping[str, float] | None,
    table: Any,
    seed: int,
    faults: Faults | None,
    duration_s: float | None,
    latency: tuple[int, int] | None,
    generated_c: GeneratedC | None = None,
    generated_controller: GeneratedController | None = None,
) -> ControllerArgs:
    """The controller arguments of a compiled run: gains, safeguards, latency, fault schedule
    and the fuzzy-PI's table, as ``runner.run`` would set them up; or, with
    ``generated_controller``, the generated C controller that replaces the loop's controller
    (its spec's safeguards set the loop's initial engagement and the path hold's rule)."""
    if generated_controller is not None:
        if table is not None or generated_c is not None:
            raise ConfigError(
                "the generated controller holds its own fuzzy surface; give no table or "
                "generated surface with it"
            )
        return _generated_args(exp, generated_controller, seed, faults, duration_s, latency)
    if controller not in DEFAULT_GAINS:
        raise ConfigError(f"unknown controller {controller!r} (expected pi or fuzzy-pi)")
    if controller == "fuzzy-pi" and table is None and generated_c is None:
        raise ConfigError(
            "the compiled fuzzy-pi needs a lookup table (load_table) or the generated C "
            "(load_generated_c)"
        )
    if table is not None and generated_c is not None:
        raise ConfigError("give the compiled fuzzy-pi a lookup table or the generated C, not both")
    if exp.controller_spec is not None:
        from fuzzkit.control.spec import with_gains

        controller, gains = spec_gains(with_gains(exp.controller_spec, gains or {}))
    faults, sensor_delay, command_delay = run_faults_and_latency(exp, seed, faults, latency)
    # The Python controller object validates the gains and holds the safeguard settings.
    hybrid = build_controller(exp, controller, gains, lambda e, de: 0.0)
    g = dict(DEFAULT_GAINS[controller])
    g.update(gains or {})
    scn = exp.scenario
    n = round((duration_s or scn.duration_s) / scn.period_s)
    spike, nan = fault_schedule(faults, n)
    rate_limit = g.get("rate_limit")
    cp = np.zeros(P.N_CP)
    cp[P.C_KIND] = P.KIND_PI if controller == "pi" else P.KIND_FUZZY
    cp[P.C_KP] = g["kp"]
    cp[P.C_KI] = g["ki"]
    cp[P.C_KX] = g.get("kx", 0.0)
    cp[P.C_UMIN] = g.get("u_min", -math.inf)
    cp[P.C_UMAX] = g.get("u_max", math.inf)
    cp[P.C_RATE] = math.nan if rate_limit is None else rate_limit
    cp[P.C_FORCE_LIMIT] = hybrid.force_limit_n
    thr = hybrid.engage_threshold_n
    cp[P.C_ENGAGE_THR] = math.nan if thr is None else thr
    cp[P.C_TRIP_SAMPLES] = hybrid.trip_samples
    cp[P.C_BACKOFF] = hybrid.backoff_m
    cp[P.C_BACKOFF_SPEED] = hybrid.backoff_speed_m_s
    cp[P.C_ENGAGE_SAMPLES] = hybrid.engage_samples
    cp[P.C_HOLD] = 1.0 if exp.hold_path_on_contact else 0.0
    cp[P.C_PERIOD] = scn.period_s
    cp[P.C_SENSOR_DELAY] = sensor_delay
    cp[P.C_COMMAND_DELAY] = command_delay
    cp[P.C_SPIKE_GATE] = hybrid.spike_gate_n
    cp[P.C_SPIKE_CONFIRM] = hybrid.spike_confirm
    cp[P.C_DROPOUT_START] = math.nan if faults.dropout is None else faults.dropout[0]
    cp[P.C_DROPOUT_LENGTH] = 0.0 if faults.dropout is None else faults.dropout[1]
    cp[P.C_SPIKE_N] = faults.spike_n
    _front_end_params(exp, cp)
    impl = "pi (compiled)"
    c_eval = None
    if generated_c is not None and controller == "fuzzy-pi":
        c_eval = generated_c.function
        impl = generated_c.label + " (compiled loop)"
    if table is not None:
        ta = table_arrays(table)
        arrays = (ta.bp0, ta.bp1, ta.values, ta.splits)
        impl = ta.label + " (compiled)"
    else:
        arrays = (
            np.array([-1.0, 1.0]),
            np.array([-1.0, 1.0]),
            np.zeros((2, 2)),
            np.zeros((1, 1), dtype=np.int64),
        )
    if exp.controller_spec is not None:
        impl = f"spec {exp.controller_spec.name}: {impl}"
    return ControllerArgs(
        cp=cp,
        selection=np.array([1.0 if s else 0.0 for s in exp.selection]),
        setpoints=np.asarray(exp.setpoints, dtype=np.float64),
        table=arrays,
        c_eval=c_eval,
        c_step=None,
        c_state=np.zeros(1),
        spike=spike,
        nan=nan,
        impl=impl,
        faults=faults,
        latency=(sensor_delay, command_delay),
        periods=n,
    )


def _generated_args(
    exp: Experiment,
    generated: GeneratedController,
    seed: int,
    faults: Faults | None,
    duration_s: float | None,
    latency: tuple[int, int] | None,
) -> ControllerArgs:
    """The compiled run's arguments around a generated controller: the loop's parameter
    vector carries only what the loop itself does (period, delays, faults, path hold, the
    initial engagement); the controller's settings are baked into its code."""
    from dataclasses import replace

    from fuzzkit.studies.task import with_spec

    # the spec's axes, set points and safeguards; the loop's own arguments built without it
    plain = replace(with_spec(exp, generated.spec), controller_spec=None)
    ctrl = controller_args(plain, "pi", None, None, seed, faults, duration_s, latency)
    ctrl.c_step = generated.step_function
    ctrl.c_state = generated.fresh_state()
    ctrl.impl = generated.label + " (compiled loop)"
    return ctrl


def _front_end_params(exp: Experiment, cp: FloatArray) -> None:
    """The sensor front end's entries of ``cp`` (none without a spec or front end): the tool's
    weight is taken at the scenario's fixed task rotation, as the Python loop passes it for a
    plant that does not turn its tool."""
    from fuzzkit.control.reference import front_end_from_spec

    fe = None if exp.controller_spec is None else front_end_from_spec(exp.controller_spec)
    cp[P.C_TARE_N] = 0.0 if fe is None else fe.tare_samples
    weight = np.zeros(3) if fe is None else fe.weight(exp.scenario.rotation)
    cp[P.C_WEIGHT : P.C_WEIGHT + 3] = weight
    cp[P.C_ALPHA] = 1.0 if fe is None else fe.alpha


def spec_gains(spec: ControllerSpec) -> tuple[str, dict[str, float]]:
    """The controller kind and the gains the compiled loop runs for a controller spec.

    Raises
    ------
    UnsupportedPlant
        The spec has different gains per axis (the compiled controller runs one set) or adapts
        them; the Python loop runs it.
    """
    if spec.adaptation.mode != "none":
        raise UnsupportedPlant(
            f"controller spec {spec.name!r} adapts its gains ({spec.adaptation.mode}); the "
            "compiled loop runs fixed gains"
        )
    first = spec.axes[0]
    if any((a.kp, a.ki, a.kx) != (first.kp, first.ki, first.kx) for a in spec.axes):
        raise UnsupportedPlant(
            f"controller spec {spec.name!r} has different gains per axis; the compiled loop "
            "runs one set"
        )
    gains = {
        "kp": first.kp,
        "ki": first.ki,
        "u_min": -spec.limits.correction_m,
        "u_max": spec.limits.correction_m,
        "rate_limit": spec.limits.step_m,
    }
    if first.kx is not None:
        gains["kx"] = first.kx
    return spec.kind, gains


def result_from_recording(
    exp: Experiment,
    plant: str,
    controller: str,
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
        controller=controller,
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
        status=rec["status"] if ctrl.c_step is not None else None,
    )


#: Kernel variants already loaded in this process: (kernel name, runs the generated C
#: surface, runs the generated C controller).
_WARMED: set[tuple[str, bool, bool]] = set()


def warm_up(
    kernel: Callable[..., Any],
    args: tuple[Any, ...],
    rec: dict[str, Any],
    scalars: Any,
    ctrl: ControllerArgs,
) -> None:
    """Run ``kernel`` over zero periods once per process and variant, with the run's argument
    types.

    The first call loads the machine code from numba's on-disk cache (or compiles it after an
    install); done here, that start-up cost stays out of the loop's CPU time. The table, the
    generated-surface and the generated-controller variants are separate specialisations
    (``c_eval`` and ``c_step`` are typed ``None`` or by the C function's signature), each
    compiled and cached once. Zero periods never call the controller, so its state is untouched.
    """
    key = (
        getattr(kernel, "__name__", repr(kernel)),
        ctrl.c_eval is not None,
        ctrl.c_step is not None,
    )
    if key in _WARMED:
        return
    state = [np.array(x, copy=True) if isinstance(x, np.ndarray) else x for x in args]
    empty = [v[:0] for v in rec.values()]
    kernel(*state, *empty, scalars.copy())
    _WARMED.add(key)
