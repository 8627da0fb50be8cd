"""The reference controller built from a spec: the behaviour generated code is checked against.

:func:`hybrid_from_spec` builds the :class:`~fuzzkit.control.controllers.HybridForceController`
(axis controllers with the spec's gains and correction limits, safety logic, sensor front end)
that the closed loop runs; :class:`Controller` wraps it in the API every generated controller
has (``step(force_n, tool_rotation=None) -> (u, status)``), one plain-float sample at a time.
A fuzzy-PI's surface is the rule base's exact engine.

Examples
--------
>>> from fuzzkit.control.spec_reader import load_spec
>>> ctrl = Controller(load_spec("docs/examples/controller_pi.yaml"))  # doctest: +SKIP
>>> u, status = ctrl.step([0.0, 0.0, 0.0], [1, 0, 0, 0, -1, 0, 0, 0, -1])  # doctest: +SKIP
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from fuzzkit.control.adaptation import SelfTuning, StiffnessSchedule
from fuzzkit.control.controllers import (
    PI,
    AxisController,
    FuzzyPI,
    HybridForceController,
    Surface,
)
from fuzzkit.control.frontend import FrontEnd
from fuzzkit.control.loop_rulebase import exact_surface
from fuzzkit.control.names import AXES
from fuzzkit.control.spec import AxisSpec, ControllerSpec, require_valid, surface_inputs
from fuzzkit.errors import ConfigError


def spec_surface(spec: ControllerSpec) -> Surface:
    """The exact engine's surface of a fuzzy-PI spec's rule base: its error and change inputs
    as :func:`fuzzkit.control.spec.surface_inputs` maps them, its first output.

    A ``table`` surface is not this one: its lookup table is built by the code generator
    (``fuzzkit.loop.controller_code.spec_surface``), which the caller passes on."""
    rb = spec.rulebase
    if rb is None:
        raise ConfigError(f"controller spec {spec.name!r}: a {spec.kind} has no rule base")
    if spec.surface.method != "exact":
        raise ConfigError(
            f"controller spec {spec.name!r}: a {spec.surface.method} surface is evaluated by "
            "its lookup table (fuzzkit.loop.controller_code.spec_surface), not exactly"
        )
    return exact_surface(rb, surface_inputs(spec, rb))


def front_end_from_spec(spec: ControllerSpec) -> FrontEnd | None:
    """The spec's sensor front end, or None when it does nothing (no tare, tool or filter)."""
    sensor = spec.sensor
    if sensor.tare_samples == 0 and sensor.tool is None and sensor.lowpass_hz is None:
        return None
    return FrontEnd(
        tare_samples=sensor.tare_samples,
        mass_kg=None if sensor.tool is None else sensor.tool.mass_kg,
        alpha=sensor.lowpass_alpha(spec.period_s),
    )


def hybrid_from_spec(spec: ControllerSpec, surface: Surface | None = None) -> HybridForceController:
    """The closed loop's controller for ``spec``.

    ``surface`` replaces a fuzzy-PI's exact engine (a lookup table, generated code); by
    default :func:`spec_surface`.

    Raises
    ------
    ConfigError
        ``spec`` breaks a rule of :func:`fuzzkit.control.spec.spec_problems`.
    """
    require_valid(spec)
    limits = {
        "u_min": -spec.limits.correction_m,
        "u_max": spec.limits.correction_m,
        "rate_limit": spec.limits.step_m,
    }
    if spec.kind == "fuzzy-pi" and surface is None:
        surface = spec_surface(spec)
    axes: list[AxisController | None] = [None, None, None]
    for a in spec.axes:
        if spec.kind == "pi":
            axes[a.index] = PI(a.kp, a.ki, **limits)
        else:
            if surface is None or a.kx is None:  # require_valid rules it out
                raise ConfigError("fuzzy-pi needs a surface and kx")
            axes[a.index] = FuzzyPI(surface, a.kp, a.ki, a.kx, **limits)
    s = spec.safety
    schedules = attach_adaptation(spec, axes)
    return HybridForceController(
        axes,
        spec.setpoints,
        period_s=spec.period_s,
        force_limit_n=s.limit_n,
        engage_threshold_n=s.engage_threshold_n,
        trip_samples=s.trip_samples,
        backoff_m=s.backoff_m,
        backoff_speed_m_s=s.backoff_speed_m_s,
        engage_samples=s.engage_samples,
        spike_gate_n=s.spike_gate,
        spike_confirm=s.spike_confirm,
        front_end=front_end_from_spec(spec),
        schedules=schedules,
    )


def input_gains(spec: ControllerSpec, a: AxisSpec) -> tuple[float, float]:
    """The self-tuning rule base's input gains ``(ge, gde)`` of axis ``a`` (1/N): ``1/error_n``
    and ``1/change_n``, or a fuzzy-PI's own ``ki`` and ``kp`` when those are not given."""
    ad = spec.adaptation
    ge = 1.0 / ad.error_n if ad.error_n is not None else a.ki
    gde = 1.0 / ad.change_n if ad.change_n is not None else a.kp
    return ge, gde


def attach_adaptation(
    spec: ControllerSpec, axes: list[AxisController | None]
) -> list[StiffnessSchedule | None]:
    """Give each axis controller the spec's adaptation; the stiffness schedules per axis (the
    hybrid controller feeds them every engaged period), None where there is none."""
    ad = spec.adaptation
    schedules: list[StiffnessSchedule | None] = [None, None, None]
    for a in spec.axes:
        c = axes[a.index]
        if not isinstance(c, PI | FuzzyPI) or ad.mode == "none":
            continue
        if ad.mode == "stiffness-scheduled":
            sched = StiffnessSchedule(ad, spec.period_s)
            schedules[a.index] = sched
            c.adapt = sched
        else:
            c.adapt = SelfTuning(ad, *input_gains(spec, a))
    return schedules


class Controller:
    """The reference controller of a spec, with the generated controllers' API.

    ``step(force_n, tool_rotation=None)`` takes one raw sensor sample (3 floats, N, task
    frame; NaN = missing) and, when the spec compensates gravity, the tool's rotation
    (9 floats, row-major, world-from-sensor); it returns the correction ``[ux, uy, uz]`` (m) to
    add to the nominal path and the status bits (:mod:`fuzzkit.control.status`).
    """

    def __init__(self, spec: ControllerSpec, surface: Surface | None = None) -> None:
        self.spec = spec
        self.hybrid = hybrid_from_spec(spec, surface)

    def reset(self) -> None:
        """Back to the initial state: u = 0, not engaged, not tripped, the tare starts again."""
        self.hybrid.reset()

    def tare(self) -> None:
        """Take the next ``sensor.tare.samples`` valid samples as a new tare (free air)."""
        self.hybrid.request_tare()

    def step(
        self, force_n: Sequence[float], tool_rotation: Sequence[float] | None = None
    ) -> tuple[list[float], int]:
        """One period: the correction (m, x y z) and the status bits."""
        if len(force_n) != len(AXES):
            raise ValueError(f"force_n needs 3 values (x, y, z), got {len(force_n)}")
        rotation = None
        if tool_rotation is not None:
            if len(tool_rotation) != 9:
                raise ValueError(
                    f"tool_rotation needs 9 values (row-major), got {len(tool_rotation)}"
                )
            rotation = np.asarray(tool_rotation, dtype=np.float64).reshape(3, 3)
        force = np.asarray([float(v) if v is not None else math.nan for v in force_n])
        u = self.hybrid.step(force, rotation)
        return [float(v) for v in u], self.hybrid.status
