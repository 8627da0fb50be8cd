"""The generated C controller: the compiled closed loop's only controller.

What ships is what runs: the controller spec of the run (the given one, or
:func:`run_controller_spec` of the run's settings) goes through ``fuzzkit compile``'s generator
(:func:`fuzzkit.loop.controller_code.open_generated`, C, double), is compiled with the strict
flags, and every period the compiled loop calls ``NAME_controller_step`` by its address
(:func:`generated_step`): the sensor front end, spike gate, engagement, trip and back-off,
the axis controllers and the correction limits are the generated code's, not the loop's.

The loop still keeps its own run bookkeeping from what the step returns (the correction and
the status bits): engagement and trip times, the fault count (a sample missing on a
force-controlled axis, or one the spike gate rejected: what the reference counts), and the
recorded ``e``, ``de``, ``du``. ``e`` is the set point minus the consumed sample on the periods
the axis controllers stepped (``ENGAGED`` and neither ``HELD`` nor ``TRIPPED``): the reference's
own ``e`` without a front end; with one, the reference's uses the compensated, filtered force.
"""

from __future__ import annotations

import hashlib
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.control import status as st
from fuzzkit.control.names import AXES
from fuzzkit.control.spec import ControllerSpec, Limits, require_valid, with_gains
from fuzzkit.errors import ConfigError
from fuzzkit.jit import jit_inline
from fuzzkit.loop.compiled.period import (
    C_PERIOD,
    C_SENSOR_DELAY,
    CS_CTRL_T,
    CS_ENGAGED,
    CS_ENGAGED_AT,
    CS_FAULTS,
    CS_TRIP_TIME,
    CS_TRIPPED,
    V_DU,
    V_E,
    V_U,
    error_change,
)
from fuzzkit.loop.task import DEFAULT_GAINS, Experiment, spec_for

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: Compiled controllers stay loaded for the life of the process, by their code's sha256.
_LOADED: dict[str, GeneratedController] = {}

_ENGAGED, _HELD, _TRIPPED, _REJECTED = st.ENGAGED, st.HELD, st.TRIPPED, st.REJECTED


@dataclass(frozen=True, slots=True)
class GeneratedController:
    """A spec's generated double C controller, compiled and loaded.

    ``step_function``: ``NAME_controller_step`` as a ctypes function; ``init_function``:
    ``NAME_controller_init``; ``set_params``: ``NAME_controller_set_params`` (through the
    loaded controller); ``state_doubles``: the size of ``NAME_controller_t`` in doubles
    (:meth:`fresh_state` makes one); ``params``: the spec's run-time parameters
    (:func:`params_of`); ``label``: the run's ``controller_impl``.
    """

    spec: ControllerSpec
    step_function: Any
    init_function: Any
    state_doubles: int
    label: str
    library: Any  # keeps the shared library mapped; its set_params sets the parameters
    params: tuple[float, ...] = ()

    def fresh_state(self) -> FloatArray:
        """A ``NAME_controller_t`` as a double array: ``NAME_controller_init``, then the spec's
        run-time parameters through ``NAME_controller_set_params``."""
        state = np.zeros(self.state_doubles)
        self.init_function(state.ctypes.data)
        if self.params:
            self.library.set_params(self.params, state.ctypes.data)
        return state


def params_of(spec: ControllerSpec) -> tuple[float, ...]:
    """The run-time parameters of ``spec`` in ``NAME_controller_params_t`` order: set points,
    kp, ki, kx per task axis x, y, z (0 on motion-only axes; kx 0 for a PI), then the
    correction and step limits."""
    by_axis = {a.axis: a for a in spec.axes}

    def per_axis(field: str) -> list[float]:
        return [float(getattr(by_axis[a], field) or 0.0) if a in by_axis else 0.0 for a in AXES]

    return (
        *per_axis("setpoint_n"),
        *per_axis("kp"),
        *per_axis("ki"),
        *per_axis("kx"),
        spec.limits.correction_m,
        spec.limits.step_m,
    )


def code_spec(spec: ControllerSpec) -> ControllerSpec:
    """The spec whose code runs ``spec``: the same with its run-time parameters (set points,
    gains, correction limits) at fixed placeholders, so that every gain set of a tune or a
    sweep runs one compiled controller, its own values set through
    ``NAME_controller_set_params``. A spec that adapts its gains keeps them (the self-tuning
    input gains are baked into its code)."""
    if spec.adaptation.mode != "none":
        return spec
    kx = 1.0 if spec.kind == "fuzzy-pi" else None
    axes = tuple(replace(a, setpoint_n=0.0, kp=1.0, ki=1.0, kx=kx) for a in spec.axes)
    return replace(spec, axes=axes, limits=Limits(1.0, 1.0))


def load_generated_controller(spec: ControllerSpec) -> GeneratedController:
    """Generate, compile and load ``spec``'s C controller (double): the code of
    :func:`code_spec`, compiled once per process and code (and kept on disk across processes,
    ``fuzzkit.codegen.toolchain.library_cache_dir``), with ``spec``'s run-time parameters.

    Raises
    ------
    ConfigError
        The spec breaks a rule of :func:`fuzzkit.control.spec.spec_problems`.
    ToolchainError
        No C compiler, or the generated code does not compile.
    """
    from fuzzkit.loop.controller_code import generate, open_generated

    require_valid(spec)
    code = code_spec(spec)
    files = generate(code, "c", "double")
    digest = hashlib.sha256()
    for path in sorted(files):
        digest.update(path.encode() + b"\0" + files[path].encode() + b"\0")
    sha = digest.hexdigest()
    if sha not in _LOADED:
        ctl = open_generated(code, "c", "double")
        label = f"generated C controller (double) {spec.name}_controller sha256 {sha[:16]}"
        _LOADED[sha] = GeneratedController(
            spec=code,
            step_function=ctl.step_function,
            init_function=ctl.init_function,
            state_doubles=len(ctl.state),
            label=label,
            library=ctl,
        )
    loaded = _LOADED[sha]
    params = () if code is spec else params_of(spec)
    return replace(loaded, spec=spec, params=params)


def run_controller_spec(
    exp: Experiment,
    controller: str,
    gains: Mapping[str, float] | None,
    rulebase: str = "macvicar_whelan",
) -> ControllerSpec:
    """The controller spec a run deploys: the experiment's own (``--spec`` or the scenario's)
    with ``gains``' ``kp``, ``ki``, ``kx`` on every axis, or else one built from the run's
    settings (``controller``, the default gains updated by ``gains``, ``rulebase``, the
    experiment's axes, set points, safety limit and engagement): the controller
    ``fuzzkit.loop.python_loop.build_controller`` builds for the same run.

    Without a ``rate_limit`` in the gains, the spec's step limit is twice its correction
    limit, which ``|du|`` cannot exceed once ``|u|`` is clamped: no step limit, as in the
    run's controller.

    Raises
    ------
    ConfigError
        An unknown controller, or settings no spec can hold (an infinite correction limit,
        gains that are not finite and positive).
    """
    if exp.controller_spec is not None:
        return require_valid(with_gains(exp.controller_spec, gains or {}))
    if controller not in DEFAULT_GAINS:
        raise ConfigError(f"unknown controller {controller!r} (expected pi or fuzzy-pi)")
    g = dict(DEFAULT_GAINS[controller])
    g.update(gains or {})
    bound = min(-g.get("u_min", -math.inf), g.get("u_max", math.inf))
    if "rate_limit" not in g and math.isfinite(bound):
        g["rate_limit"] = 2.0 * bound
    rb = None
    if controller == "fuzzy-pi":
        from fuzzkit.formats.registry import load

        rb = load(rulebase)
    name = re.sub(r"\W", "_", f"{exp.name}_{controller}", flags=re.ASCII)
    if not name[:1].isalpha():
        name = "run_" + name
    return require_valid(spec_for(exp, controller, g, name, rb, rulebase if rb else None))


@jit_inline
def generated_step(
    c_step: Any,
    c_state: FloatArray,
    c_rot: FloatArray,
    cp: FloatArray,
    selection: FloatArray,
    setpoints: FloatArray,
    consumed: FloatArray,
    t_s: float,
    cs: FloatArray,
    cv: FloatArray,
    correction: FloatArray,
) -> int:
    """One period of the generated controller on the consumed sample; returns its status.

    ``c_step`` is ``NAME_controller_step`` (ctypes: numba reads its address at every call of
    the kernel), ``c_state`` its ``NAME_controller_t``, ``c_rot`` the tool's rotation
    (row-major 9). Writes ``correction`` and keeps the loop's bookkeeping in ``cs``, ``cv``
    (:func:`loop_bookkeeping`).
    """
    status = int(c_step(c_state.ctypes, consumed.ctypes, c_rot.ctypes, correction.ctypes))
    loop_bookkeeping(cs, cv, cp, selection, setpoints, status, consumed, correction, t_s)
    return status


@jit_inline
def loop_bookkeeping(
    cs: FloatArray,
    cv: FloatArray,
    cp: FloatArray,
    selection: FloatArray,
    setpoints: FloatArray,
    status: int,
    consumed: FloatArray,
    correction: FloatArray,
    t_s: float,
) -> None:
    """The loop's record, in ``cs`` and ``cv``, of one step of a generated controller (C or
    Python) in a run with parameters ``cp``, ``selection`` and ``setpoints``: from the status
    the step returned and the correction it wrote for the ``consumed`` sample at ``t_s``.

    Keeps (:mod:`fuzzkit.loop.compiled.period`) the engagement and
    trip times, the fault count (a sample missing on a force-controlled axis after the
    start-up's sensor-delay periods, or one the spike gate rejected: what the reference
    counts) and the recorded ``e``, ``de``, ``du``, ``u`` of the periods the axis controllers
    stepped.
    """
    cs[CS_CTRL_T] += cp[C_PERIOD]
    u, e, du = cv[V_U], cv[V_E], cv[V_DU]
    missing = False
    for i in range(3):
        if selection[i] > 0.0 and not math.isfinite(consumed[i]):
            missing = True
    # as the reference counts them: a missing sample within the first sensor-delay periods is
    # the start-up wait (no measurement can have arrived yet), not a sensor fault
    started = round(cs[CS_CTRL_T] / cp[C_PERIOD]) > cp[C_SENSOR_DELAY]
    if (missing and started) or status & _REJECTED:
        cs[CS_FAULTS] += 1.0
    if status & _TRIPPED and cs[CS_TRIPPED] == 0.0:
        cs[CS_TRIPPED] = 1.0
        cs[CS_TRIP_TIME] = cs[CS_CTRL_T]
    if status & _ENGAGED:
        cs[CS_ENGAGED] = 1.0
        if math.isnan(cs[CS_ENGAGED_AT]):
            cs[CS_ENGAGED_AT] = t_s
    du[:] = 0.0
    stepped = status & _ENGAGED and not status & (_HELD | _TRIPPED)
    if stepped:
        for i in range(3):
            if selection[i] > 0.0:
                du[i] = correction[i] - u[i]
                u[i] = correction[i]
                e[i] = setpoints[i] - consumed[i]
        error_change(cs, cv)
