"""A spec's generated controller in the Python loop: C where a compiler exists, else the
generated Python, behind what :func:`fuzzkit.loop.python_loop.run` drives.

The Python loop runs the plants the compiled loop does not model (MuJoCo) and the scenarios
its kernels lack (a tool's weight, a drifting bias, a tilted task frame); with this controller
those runs execute the code ``fuzzkit compile`` emits, as the compiled loop does, and not the
reference (which stays available with ``--controller-impl reference``). The loop's record of each
step (engagement and trip times, the fault count, ``e``, ``de``, ``du``) is the compiled
loop's own, :func:`fuzzkit.loop.compiled.generated_controller.loop_bookkeeping`, so that the
two loops record a step alike and ``fuzzkit replay`` of the run's CSV reproduces it.
"""

from __future__ import annotations

import ctypes
import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.control.spec import ControllerSpec
from fuzzkit.errors import ConfigError, ToolchainError
from fuzzkit.loop.compiled import period as P
from fuzzkit.loop.compiled.generated_controller import (
    code_spec,
    load_generated_controller,
    loop_bookkeeping,
    params_of,
)

FloatArray = npt.NDArray[np.float64]
#: one step of a generated controller: (sample, rotation row-major 9) -> status, writing the
#: correction into the array it was given
StepFunction = Callable[[FloatArray, FloatArray, FloatArray], int]


#: The generated controller's implementations, as ``--controller-impl`` names them
#: (``fuzzkit.loop.spec.CONTROLLER_IMPLS`` less the reference; ``ros2 --impl`` has these).
GENERATED_IMPLS = ("auto", "c", "python")


def open_generated_impl(
    spec: ControllerSpec, impl: str, number_type: str | None = None
) -> tuple[str, Any]:
    """The spec's generated controller as ``impl`` names it
    (:data:`GENERATED_IMPLS`), opened (:func:`open_generated`): ``(target that
    runs it, the controller)``. ``number_type``: the C's (the Python computes in double).

    Raises
    ------
    ToolchainError
        ``c`` and no compiler, or code that does not compile.
    ConfigError
        An unknown ``impl``.
    """
    from fuzzkit.loop.controller_code import open_generated

    if impl not in GENERATED_IMPLS:
        raise ConfigError(
            f"unknown generated implementation {impl!r} (expected {', '.join(GENERATED_IMPLS)})"
        )
    if impl in ("auto", "c"):
        try:
            return "c", open_generated(spec, "c", number_type)
        except ToolchainError:
            if impl == "c":
                raise
    return "python", open_generated(spec, "python")


def open_step(spec: ControllerSpec, impl: str = "auto") -> tuple[StepFunction, str]:
    """The generated controller of ``spec`` as one step function, and its label: the double C
    (``impl`` ``c``, or ``auto`` where a C compiler exists; compiled once per process and code,
    :func:`load_generated_controller`), or the generated Python module (``python``, or
    ``auto`` without a C compiler; ``c`` raises the ToolchainError)."""
    if impl == "python":
        return _python_step(spec, "asked for")
    try:
        gen = load_generated_controller(spec)
    except ToolchainError as exc:
        if impl == "c":
            raise
        return _python_step(spec, f"no C compiler: {exc}")
    return _CStep(gen), gen.label


def adaptation_of(step: StepFunction) -> tuple[FloatArray, FloatArray]:
    """The gain factor and the stiffness estimate per task axis (N/mm) after the last call of
    ``step``, an adapting spec's generated controller as :func:`open_step` opens it."""
    read = getattr(step, "adaptation", None)
    if read is None:
        raise ConfigError("this step function does not report its adaptation")
    factor, k = read()
    return np.asarray(factor, dtype=np.float64), np.asarray(k, dtype=np.float64)


class _CStep:
    """``NAME_controller_step`` on a state of its own (a ``NAME_controller_t`` as doubles), and
    ``NAME_controller_adaptation`` of that state where the spec adapts its gains."""

    def __init__(self, gen: Any) -> None:
        self.fn, self.state = gen.step_function, gen.fresh_state()
        self.read = gen.library.adaptation_function
        self.ptr = ctypes.POINTER(ctypes.c_double)
        self._factor, self._k = np.zeros(3), np.zeros(3)

    def __call__(self, force: FloatArray, rotation: FloatArray, out: FloatArray) -> int:
        f, r, o = (a.ctypes.data_as(self.ptr) for a in (force, rotation, out))
        return int(self.fn(self.state.ctypes.data, f, r, o))

    def adaptation(self) -> tuple[FloatArray, FloatArray]:
        """The gain factor and stiffness estimate per axis after the last step."""
        f, k = (a.ctypes.data_as(self.ptr) for a in (self._factor, self._k))
        self.read(self.state.ctypes.data, f, k, None)
        return self._factor.copy(), self._k.copy()


class _PythonStep:
    """The generated Python controller's ``step`` (and ``adaptation``) as a step function."""

    def __init__(self, ctl: Any) -> None:
        self.ctl = ctl

    def __call__(self, force: FloatArray, rotation: FloatArray, out: FloatArray) -> int:
        u, status = self.ctl.step(force.tolist(), rotation.tolist())
        out[:] = u
        return int(status)

    def adaptation(self) -> tuple[list[float], list[float]]:
        """The gain factor and stiffness estimate per axis after the last step."""
        factor, k, _ = self.ctl.adaptation()
        return factor, k


def _python_step(spec: ControllerSpec, why: str) -> tuple[StepFunction, str]:
    from fuzzkit.loop.controller_code import open_generated

    code = code_spec(spec)
    ctl = open_generated(code, "python")
    if code is not spec:
        ctl.set_params(params_of(spec))
    return _PythonStep(ctl), f"generated Python controller {spec.name}_controller ({why})"


def run_controller(
    exp: Any,
    controller: str,
    gains: Mapping[str, float],
    rulebase: str,
    seed: int,
    faults: Any,
    latency: tuple[int, int] | None,
    impl: str = "auto",
    step: tuple[StepFunction, str] | None = None,
) -> GeneratedLoopController:
    """The generated controller of a Python-loop run: the run's controller spec
    (:func:`~fuzzkit.loop.compiled.generated_controller.run_controller_spec` of ``exp``,
    ``controller``, ``gains``, ``rulebase``) with the run's sensor delay (its ``faults``,
    seeded by ``seed``, and ``latency``, as :func:`fuzzkit.loop.python_loop.run` sets them), in
    the implementation ``impl`` (:func:`open_step`), or stepped by ``step`` (see
    :class:`GeneratedLoopController`)."""
    from fuzzkit.loop.compiled.generated_controller import run_controller_spec
    from fuzzkit.loop.timing import run_faults_and_latency

    spec = run_controller_spec(exp, controller, gains, rulebase)
    _, sensor_delay, _ = run_faults_and_latency(exp, seed, faults, latency)
    return GeneratedLoopController(spec, sensor_delay, impl, step)


class GeneratedLoopController:
    """The generated controller of ``spec`` with the attributes the Python loop reads of a
    :class:`~fuzzkit.control.controllers.HybridForceController`: ``step``, ``wait``, the
    status bits, engagement, trip, fault count and the recorded ``e``, ``de``, ``du``.

    ``sensor_delay``: the run's sensor delay in periods (a fault's delay included,
    ``fuzzkit.loop.timing.run_faults_and_latency``): the start-up periods in which a missing
    sample is no sensor fault. ``step``: a step function and its label that take the generated
    controller's steps instead of one opened here (:func:`open_step`): the ROS 2 closed loop's
    plant node, whose steps are the controller node's over the middleware.
    """

    #: no reference axis controllers (nothing to adapt from the loop's side)
    controllers: tuple[Any, ...] = ()

    def __init__(
        self,
        spec: ControllerSpec,
        sensor_delay: int,
        impl: str = "auto",
        step: tuple[StepFunction, str] | None = None,
    ) -> None:
        self.spec = spec
        self.kind = spec.kind
        self._step, self.label = open_step(spec, impl) if step is None else step
        self.cp = np.zeros(P.N_CP)
        thr = spec.safety.engage_threshold_n
        self.cp[P.C_ENGAGE_THR] = math.nan if thr is None else thr
        self.cp[P.C_PERIOD] = spec.period_s
        self.cp[P.C_SENSOR_DELAY] = sensor_delay
        self.selection = np.array([1.0 if s else 0.0 for s in spec.selection])
        self.setpoints = np.asarray(spec.setpoints, dtype=np.float64)
        self.cs, self.cv = P.controller_state(self.cp)
        #: the spec adapts its gains: the gain factor and the stiffness estimate (N/mm) per
        #: axis after each step, read from the generated code
        self.adaptive = spec.adaptation.mode != "none"
        if self.adaptive and getattr(self._step, "adaptation", None) is None:
            raise ConfigError(
                f"spec {spec.name!r} adapts its gains, and this step function does not report "
                "its gain factor and stiffness estimate"
            )
        self.gain_scale = np.ones(3)
        self.stiffness_n_mm = np.full(3, math.nan)
        self._sample = np.zeros(3)
        self._rotation = np.zeros(9)
        self._out = np.zeros(3)
        self.status = 0

    def step(self, force: FloatArray | None, rotation: FloatArray | None = None) -> FloatArray:
        """One period on the consumed sample (N, task frame; NaN: missing) and the tool's
        rotation (3x3 world-from-sensor): the correction (m, task frame)."""
        self._sample[:] = math.nan if force is None else force
        if rotation is None:
            self._rotation[:] = math.nan
        else:
            self._rotation[:] = np.asarray(rotation, dtype=np.float64).reshape(9)
        self.status = self._step(self._sample, self._rotation, self._out)
        if self.adaptive:
            self.gain_scale, self.stiffness_n_mm = adaptation_of(self._step)
        t_s = self.cs[P.CS_CTRL_T] + self.cp[P.C_PERIOD]  # the controller's clock
        loop_bookkeeping(
            self.cs,
            self.cv,
            self.cp,
            self.selection,
            self.setpoints,
            self.status,
            self._sample,
            self._out,
            t_s,
        )
        return self._out.copy()

    def wait(self) -> FloatArray:
        """A start-up period with no measurement yet: the generated step on a missing sample,
        as the compiled loop calls it (not counted as a fault)."""
        return self.step(None)

    @property
    def engaged(self) -> bool:
        return bool(self.cs[P.CS_ENGAGED] > 0.0)

    @property
    def tripped(self) -> bool:
        return bool(self.cs[P.CS_TRIPPED] > 0.0)

    @property
    def faults(self) -> int:
        return int(self.cs[P.CS_FAULTS])

    @property
    def trip_time_s(self) -> float | None:
        t = float(self.cs[P.CS_TRIP_TIME])
        return None if math.isnan(t) else t

    @property
    def e(self) -> FloatArray:
        return np.asarray(self.cv[P.V_E], dtype=np.float64)

    @property
    def de(self) -> FloatArray:
        return np.asarray(self.cv[P.V_DE], dtype=np.float64)

    @property
    def du(self) -> FloatArray:
        return np.asarray(self.cv[P.V_DU], dtype=np.float64)
