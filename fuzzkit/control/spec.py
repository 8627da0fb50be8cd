"""The controller spec: everything the deployed outer force loop is, as one frozen object.

A spec is read from YAML by :mod:`fuzzkit.control.spec_reader` (format: ``docs/controller.md``;
JSON Schema: :mod:`fuzzkit.control.spec_schema`). The reference controller is built from it
(:mod:`fuzzkit.control.reference`), and every code generator reads the same object: a setting
that is not here does not exist in the deployed controller.

Units are in the field names (``_n`` newtons, ``_m`` metres, ``_s`` seconds, ``_hz`` hertz,
``_kg`` kilograms). Frames and signs are those of ``docs/controller.md`` ("Frames and signs"):
forces are what the tool exerts on the environment, in the controller's frame (the wrist
sensor's frame, which is the task frame of a tool pointing straight down), and a positive
correction moves the tool into the surface.

:func:`spec_problems` holds the semantic checks (finite gains, a safety limit above every set
point ...). The reader reports them at the YAML position of the value; programmatic users call
:func:`require_valid`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

from fuzzkit.control.adaptation_spec import MODES, NONE, Adaptation, adaptation_problems
from fuzzkit.control.names import AXES, KINDS
from fuzzkit.errors import ConfigError
from fuzzkit.fuzzy.model import RuleBase, Source
from fuzzkit.fuzzy.validation import identifier_problem

#: Adaptation modes (:mod:`fuzzkit.control.adaptation_spec`).
ADAPTATIONS = MODES
#: Standard gravity (m/s^2, CGPM 1901), the magnitude of the tool's weight per kilogram.
STANDARD_GRAVITY_M_S2 = 9.80665

#: The sample periods a spec may have (s): 100 kHz to 0.1 Hz.
MIN_PERIOD_S = 1e-5
MAX_PERIOD_S = 10.0

#: ``safety.watchdog.periods`` when the spec leaves it out.
DEFAULT_WATCHDOG_PERIODS = 10

#: A logical position in a spec: the YAML keys leading to a value (``("axes", "z", "kp")``).
SpecPath = tuple[str, ...]

#: How a fuzzy-PI may evaluate its rule base's surface (``surface.method``).
SURFACE_METHODS = ("exact", "table")
#: Breakpoints per input a table may have (``surface.resolution``); the code generator's bounds.
MIN_RESOLUTION = 2
MAX_RESOLUTION = 4096


@dataclass(frozen=True, slots=True)
class Surface:
    """How the fuzzy-PI evaluates its rule base's surface, for every consumer of the spec.

    ``method``: ``exact`` (the default: exact inference, rounding error only) or ``table`` (a
    lookup table, for targets that need one). A table is sized by ``tolerance`` (the certified
    largest error, a fraction of the output's range) or by ``resolution`` (breakpoints per
    input), exactly one of the two.
    """

    method: str = "exact"
    tolerance: float | None = None
    resolution: int | None = None


#: The default surface: exact inference.
EXACT = Surface()


@dataclass(frozen=True, slots=True)
class AxisSpec:
    """One force-controlled task axis: its set point and gains.

    PI: ``kp``, ``ki`` in m/N (``du = kp*de + ki*e``). Fuzzy-PI: ``ki`` scales the error and
    ``kp`` its change (1/N), ``kx`` scales the surface's output (m per period);
    ``du = kx * F(clip(ki*e), clip(kp*de))``. ``kx`` is None for PI.
    """

    axis: str
    setpoint_n: float
    kp: float
    ki: float
    kx: float | None = None

    @property
    def index(self) -> int:
        """0, 1, 2 for x, y, z."""
        return AXES.index(self.axis)


@dataclass(frozen=True, slots=True)
class Limits:
    """Correction limits: ``|u| <= correction_m`` per axis (the anti-windup of the incremental
    form) and ``|du| <= step_m`` per period (m)."""

    correction_m: float
    step_m: float


@dataclass(frozen=True, slots=True)
class Safety:
    """The safeguards of :class:`~fuzzkit.control.controllers.HybridForceController`.

    ``limit_n``: the force safety limit (N, on every axis); ``trip_samples`` consecutive samples
    above it trip the controller, which then backs off ``backoff_m`` (m) against the measured
    force at ``backoff_speed_m_s`` (m/s). ``engage_threshold_n``: the loop engages once
    ``engage_samples`` consecutive valid samples exceed it on some axis (None: engaged from the
    start). ``spike_gate_n``: a sample jumping more than this (N) from the last accepted one is
    rejected, unless ``spike_confirm`` samples in a row were. ``watchdog_periods``: a deployed
    loop (``fuzzkit ros2``) stops its output when no sample came for this many periods.
    """

    limit_n: float
    engage_threshold_n: float | None = 1.0
    engage_samples: int = 3
    spike_gate_n: float | None = None  # None: half of limit_n
    spike_confirm: int = 4
    trip_samples: int = 2
    backoff_m: float = 0.005
    backoff_speed_m_s: float = 0.02
    watchdog_periods: int = DEFAULT_WATCHDOG_PERIODS

    @property
    def spike_gate(self) -> float:
        """The spike gate in force (N): ``spike_gate_n``, or half the safety limit."""
        return 0.5 * self.limit_n if self.spike_gate_n is None else self.spike_gate_n


@dataclass(frozen=True, slots=True)
class ToolSpec:
    """The tool below the wrist sensor: its mass (kg) and centre of mass (m, sensor frame).

    The weight ``mass_kg * g`` is subtracted from every force sample given the tool's rotation.
    A weight is a pure force wherever it acts, so the force compensation does not depend on
    ``com_m``; it is the lever arm of the weight's torque, kept for sensors that report torques.
    """

    mass_kg: float
    com_m: tuple[float, float, float] = (0.0, 0.0, 0.0)


@dataclass(frozen=True, slots=True)
class SensorSpec:
    """The sensor front end, applied to each raw sample before ``e = f_d - f``.

    ``tare_samples``: the bias is the mean of the first N valid (free-air) samples, and of the
    N after each tare request (0: no tare, bias 0). ``tool``: gravity compensation (None: off).
    ``lowpass_hz``: corner of the first-order low-pass (None: no filter).
    """

    tare_samples: int = 0
    tool: ToolSpec | None = None
    lowpass_hz: float | None = None

    def lowpass_alpha(self, period_s: float) -> float:
        """The filter's gain per period: ``y += alpha * (x - y)``.

        ``alpha = 1 - exp(-2*pi*fc*T)``: the exact discretisation (zero-order hold) of the
        continuous ``tau*y' + y = x`` with ``tau = 1 / (2*pi*fc)``; 1 (no filter) without a
        corner.
        """
        if self.lowpass_hz is None:
            return 1.0
        return 1.0 - math.exp(-2.0 * math.pi * self.lowpass_hz * period_s)


@dataclass(frozen=True, slots=True)
class ControllerSpec:
    """The whole outer-loop controller: what ships, what the closed loop verifies.

    ``axes`` lists the force-controlled task axes (the selection matrix S) in x, y, z order;
    the others follow the nominal path. ``rulebase`` is the loaded rule base of a fuzzy-PI
    (``rulebase_ref``: the name or path as written; ``rulebase_source``: the shipped name or
    the resolved path, what ``fuzzkit.formats.registry.load`` takes; None for PI).
    ``adaptation``: how the scaling factors adapt online (mode none: fixed). ``source``:
    the spec file and the sha256 of its text (None when built in code). ``surface``: how the
    rule base's surface is evaluated (:class:`Surface`). ``inputs``: the rule base's input
    names in role order (error, change of error); None: by position (first input the error).
    """

    name: str
    kind: str
    period_s: float
    axes: tuple[AxisSpec, ...]
    limits: Limits
    safety: Safety
    sensor: SensorSpec = field(default_factory=SensorSpec)
    rulebase: RuleBase | None = None
    rulebase_ref: str | None = None
    rulebase_source: str | None = None
    adaptation: Adaptation = NONE
    description: str = ""
    source: Source | None = None
    surface: Surface = EXACT
    inputs: tuple[str, str] | None = None

    @property
    def selection(self) -> tuple[bool, bool, bool]:
        """The diagonal of S: True for a force-controlled axis (x, y, z)."""
        chosen = {a.axis for a in self.axes}
        return ("x" in chosen, "y" in chosen, "z" in chosen)

    @property
    def setpoints(self) -> tuple[float, float, float]:
        """Set points per task axis (N); 0 on motion-only axes."""
        out = [0.0, 0.0, 0.0]
        for a in self.axes:
            out[a.index] = a.setpoint_n
        return (out[0], out[1], out[2])

    def axis(self, name: str) -> AxisSpec | None:
        """The spec of task axis ``name`` (x, y, z), or None when it is not force controlled."""
        return next((a for a in self.axes if a.axis == name), None)


def _finite(value: float | None) -> bool:
    return value is not None and math.isfinite(value)


def _positive(problems: list[tuple[SpecPath, str]], path: SpecPath, value: float | None) -> None:
    if value is not None and not (math.isfinite(value) and value > 0.0):
        problems.append((path, f"{'.'.join(path)} must be a finite number > 0 (got {value!r})"))


def _count(problems: list[tuple[SpecPath, str]], path: SpecPath, value: int, low: int) -> None:
    if value < low:
        problems.append((path, f"{'.'.join(path)} must be an integer >= {low} (got {value})"))


def _axis_problems(spec: ControllerSpec, a: AxisSpec) -> list[tuple[SpecPath, str]]:
    out: list[tuple[SpecPath, str]] = []
    base: SpecPath = ("axes", a.axis)
    if a.axis not in AXES:
        out.append((base, f"no task axis {a.axis!r}; expected x, y or z"))
    if not _finite(a.setpoint_n):
        out.append(((*base, "setpoint_n"), f"setpoint_n must be finite (got {a.setpoint_n!r})"))
    elif _finite(spec.safety.limit_n) and abs(a.setpoint_n) >= spec.safety.limit_n:
        # A set point at or beyond the safety limit trips the controller in its steady state.
        out.append(
            (
                (*base, "setpoint_n"),
                f"set point {a.setpoint_n:g} N is not below the safety limit "
                f"{spec.safety.limit_n:g} N (safety.limit_n); the loop would trip at rest",
            )
        )
    gains: list[tuple[str, float | None]] = [("kp", a.kp), ("ki", a.ki)]
    if spec.kind == "fuzzy-pi":
        gains.append(("kx", a.kx))
        if a.kx is None:
            out.append(((*base, "gains"), "fuzzy-pi needs gains kx (m per period)"))
    elif a.kx is not None:
        out.append(((*base, "gains", "kx"), "kx is a fuzzy-pi gain; a pi takes kp and ki"))
    for key, value in gains:
        if value is None:
            continue
        path = (*base, "gains", key)
        if not math.isfinite(value):
            out.append((path, f"gain {key} must be finite (got {value!r})"))
        elif spec.kind == "fuzzy-pi" and value <= 0.0:
            out.append((path, f"fuzzy-pi gain {key} must be > 0 (got {value!r})"))
        elif value < 0.0:
            out.append((path, f"pi gain {key} must be >= 0 (got {value!r})"))
    return out


def spec_problems(spec: ControllerSpec) -> list[tuple[SpecPath, str]]:
    """Every semantic problem of ``spec``, each with the YAML path of the value at fault.

    Structural problems (types, unknown keys) are the reader's; these are the rules a spec built
    in code must obey too.
    """
    out: list[tuple[SpecPath, str]] = []
    why = identifier_problem(spec.name)
    if why is not None:
        out.append((("name",), f"name: {why} (it prefixes the generated C symbols)"))
    if spec.kind not in KINDS:
        out.append((("controller",), f"unknown controller {spec.kind!r}; expected pi or fuzzy-pi"))
    if spec.kind == "fuzzy-pi" and spec.rulebase is None:
        out.append((("rulebase",), "fuzzy-pi needs a rule base (a shipped name or a path)"))
    if spec.kind == "pi" and spec.rulebase_ref is not None:
        out.append((("rulebase",), "a pi controller takes no rule base"))
    if spec.rulebase is not None:
        out += [(("rulebase",), p) for p in rulebase_problems(spec.rulebase)]
        if spec.inputs is not None:
            out += [(("inputs",), p) for p in input_problems(spec.inputs, spec.rulebase)]
    elif spec.kind == "pi" and spec.inputs is not None:
        out.append((("inputs",), "a pi controller has no rule base to map inputs of"))
    out += surface_problems(spec.surface, spec.kind)
    out += adaptation_problems(spec.adaptation, spec.kind, spec.period_s)
    _positive(out, ("period_s",), spec.period_s)
    if _finite(spec.period_s) and not MIN_PERIOD_S <= spec.period_s <= MAX_PERIOD_S:
        out.append(
            (
                ("period_s",),
                f"period_s must be in [{MIN_PERIOD_S:g}, {MAX_PERIOD_S:g}] s "
                f"(got {spec.period_s:g})",
            )
        )
    if not spec.axes:
        out.append((("axes",), "axes needs at least one force-controlled axis (x, y or z)"))
    names = [a.axis for a in spec.axes]
    for dup in sorted({n for n in names if names.count(n) > 1}):
        out.append((("axes", dup), f"axis {dup} is listed twice"))
    if [n for n in AXES if n in names] != names:
        out.append((("axes",), "axes must be listed in x, y, z order"))
    for a in spec.axes:
        out += _axis_problems(spec, a)
    _positive(out, ("limits", "correction_m"), spec.limits.correction_m)
    _positive(out, ("limits", "step_m"), spec.limits.step_m)
    s = spec.safety
    _positive(out, ("safety", "limit_n"), s.limit_n)
    if s.engage_threshold_n is not None:
        if not (math.isfinite(s.engage_threshold_n) and s.engage_threshold_n >= 0.0):
            out.append(
                (
                    ("safety", "engage", "threshold_n"),
                    f"threshold_n must be a finite number >= 0 or null "
                    f"(got {s.engage_threshold_n!r})",
                )
            )
        elif _finite(s.limit_n) and s.engage_threshold_n >= s.limit_n:
            out.append(
                (
                    ("safety", "engage", "threshold_n"),
                    f"engage threshold {s.engage_threshold_n:g} N is not below the safety "
                    f"limit {s.limit_n:g} N",
                )
            )
    _count(out, ("safety", "engage", "samples"), s.engage_samples, 1)
    _positive(out, ("safety", "spike_gate", "threshold_n"), s.spike_gate_n)
    _count(out, ("safety", "spike_gate", "confirm"), s.spike_confirm, 1)
    _count(out, ("safety", "trip", "samples"), s.trip_samples, 1)
    _count(out, ("safety", "watchdog", "periods"), s.watchdog_periods, 1)
    _positive(out, ("safety", "backoff", "distance_m"), s.backoff_m)
    _positive(out, ("safety", "backoff", "speed_m_s"), s.backoff_speed_m_s)
    out += _sensor_problems(spec)
    return out


def _sensor_problems(spec: ControllerSpec) -> list[tuple[SpecPath, str]]:
    out: list[tuple[SpecPath, str]] = []
    sensor = spec.sensor
    _count(out, ("sensor", "tare", "samples"), sensor.tare_samples, 0)
    if sensor.tool is not None:
        if not (math.isfinite(sensor.tool.mass_kg) and sensor.tool.mass_kg >= 0.0):
            out.append(
                (
                    ("sensor", "tool", "mass_kg"),
                    f"mass_kg must be a finite number >= 0 (got {sensor.tool.mass_kg!r})",
                )
            )
        if len(sensor.tool.com_m) != 3 or not all(math.isfinite(c) for c in sensor.tool.com_m):
            out.append((("sensor", "tool", "com_m"), "com_m must be 3 finite numbers (x, y, z)"))
    fc = sensor.lowpass_hz
    _positive(out, ("sensor", "lowpass_hz"), fc)
    if fc is not None and _finite(spec.period_s) and spec.period_s > 0.0:
        nyquist = 0.5 / spec.period_s
        if math.isfinite(fc) and fc >= nyquist:
            out.append(
                (
                    ("sensor", "lowpass_hz"),
                    f"lowpass_hz {fc:g} is not below the Nyquist frequency {nyquist:g} Hz "
                    f"of period_s {spec.period_s:g}",
                )
            )
        elif math.isfinite(fc) and fc > 0.0 and not sensor.lowpass_alpha(spec.period_s) > 0.0:
            out.append(
                (
                    ("sensor", "lowpass_hz"),
                    f"lowpass_hz {fc:g} is too low for period_s {spec.period_s:g}: the filter "
                    "would never move (its gain per period rounds to 0)",
                )
            )
    return out


def surface_problems(surface: Surface, kind: str) -> list[tuple[SpecPath, str]]:
    """What is wrong with the ``surface:`` section (empty when nothing)."""
    out: list[tuple[SpecPath, str]] = []
    path: SpecPath = ("surface",)
    if surface.method not in SURFACE_METHODS:
        out.append(
            (
                (*path, "method"),
                f"unknown surface method {surface.method!r}; expected exact or table",
            )
        )
        return out
    if kind == "pi" and surface != EXACT:
        out.append((path, "a pi controller has no surface; remove 'surface' (or write exact)"))
        return out
    tol, res = surface.tolerance, surface.resolution
    if surface.method == "exact":
        if tol is not None or res is not None:
            out.append((path, "an exact surface takes no tolerance or resolution"))
        return out
    if (tol is None) == (res is None):
        out.append(
            (path, "a table surface needs exactly one of tolerance (e.g. 0.001) or resolution")
        )
    if tol is not None and not (math.isfinite(tol) and 0.0 < tol < 1.0):
        out.append(
            (
                (*path, "tolerance"),
                f"tolerance is a fraction of the output's range, in (0, 1) (got {tol!r})",
            )
        )
    if res is not None and not MIN_RESOLUTION <= res <= MAX_RESOLUTION:
        out.append(
            (
                (*path, "resolution"),
                f"resolution must be {MIN_RESOLUTION} to {MAX_RESOLUTION} breakpoints per "
                f"input (got {res})",
            )
        )
    return out


def input_problems(inputs: tuple[str, str], rb: RuleBase) -> list[str]:
    """Why ``inputs`` (error, change) does not name two distinct inputs of ``rb``."""
    names = rb.input_names
    out = [
        f"{role} input {name!r} is not an input of rule base {rb.name!r} "
        f"(its inputs: {', '.join(names)})"
        for role, name in zip(("error", "change"), inputs, strict=True)
        if name not in names
    ]
    if inputs[0] == inputs[1]:
        out.append(f"the error and change inputs must differ (both {inputs[0]!r})")
    return out


def surface_inputs(spec: ControllerSpec, rb: RuleBase) -> tuple[int, int]:
    """The positions in ``rb`` of the error and change-of-error inputs under ``spec``'s roles.

    Every consumer (reference controller, code generation, certificate) maps roles through
    here: by ``spec.inputs`` when given, else by position (first input the error).

    Raises
    ------
    ConfigError
        ``rb`` does not have two inputs, or ``spec.inputs`` does not name them.
    """
    if len(rb.inputs) != 2:
        raise ConfigError(
            f"rule base {rb.name!r} has {len(rb.inputs)} inputs; a fuzzy-PI needs exactly 2"
        )
    if spec.inputs is None:
        return (0, 1)
    problems = input_problems(spec.inputs, rb)
    if problems:
        raise ConfigError(f"controller spec {spec.name!r}: inputs: " + "; ".join(problems))
    names = rb.input_names
    return (names.index(spec.inputs[0]), names.index(spec.inputs[1]))


def role_ordered(spec: ControllerSpec, rb: RuleBase) -> RuleBase:
    """``rb`` with its inputs in role order (error, change): what a consumer that takes the
    surface's inputs by position (generated code) evaluates. ``rb`` itself when already so."""
    i_e, i_de = surface_inputs(spec, rb)
    if (i_e, i_de) == (0, 1):
        return rb
    return replace(rb, inputs=(rb.inputs[i_e], rb.inputs[i_de]))


def rulebase_problems(rb: RuleBase) -> list[str]:
    """Why ``rb`` cannot be a fuzzy-PI's surface (empty when it can).

    A fuzzy-PI reads two inputs, the scaled error and the scaled change of error (both
    clipped to [-1, 1]; which is which: :func:`surface_inputs`), and its first output as
    ``du`` before ``kx``.
    """
    out: list[str] = []
    if len(rb.inputs) != 2:
        out.append(
            f"rule base {rb.name!r} has {len(rb.inputs)} inputs; a fuzzy-PI needs exactly 2 "
            "(the scaled error and its change)"
        )
    for var in rb.inputs[:2]:
        if (var.low, var.high) != (-1.0, 1.0):
            out.append(
                f"rule base {rb.name!r}: input {var.name} spans [{var.low:g}, {var.high:g}]; a "
                "fuzzy-PI clips its scaled inputs to [-1, 1], so the range must be [-1, 1]"
            )
    if not rb.outputs:
        out.append(f"rule base {rb.name!r} has no output")
    return out


def lead_axis(spec: ControllerSpec) -> AxisSpec:
    """The axis a single gain set names: the one with the largest ``|setpoint_n|`` (the first
    listed of equal ones), the axis that regulates the contact force."""
    return max(spec.axes, key=lambda a: abs(a.setpoint_n))


def with_gains(spec: ControllerSpec, gains: Mapping[str, float]) -> ControllerSpec:
    """``spec`` with ``gains``' ``kp``, ``ki`` (and ``kx``) on its :func:`lead_axis`, and every
    other axis's gain scaled by the same factor, so that it keeps its ratio to the lead's
    (what tuning a spec tries). On a spec whose axes share their gains, that is ``gains`` on
    every axis; ``gains`` equal to the lead's own give ``spec`` back, bit for bit. Where the
    lead's gain is 0 no factor exists: an axis with a gain of 0 takes ``gains``' value and one
    with another keeps its own. Other keys (the gains files' ``u_min``, ``rate_limit`` ...) do
    not change the spec's limits, which are deployment settings."""
    lead = lead_axis(spec)

    def scaled(own: float, lead_own: float, key: str) -> float:
        if key not in gains:
            return own
        if lead_own == 0.0:
            return gains[key] if own == 0.0 else own
        return own * (gains[key] / lead_own)

    def moved(a: AxisSpec) -> AxisSpec:
        kx = a.kx
        if spec.kind == "fuzzy-pi" and a.kx is not None and lead.kx is not None:
            kx = scaled(a.kx, lead.kx, "kx")
        return replace(a, kp=scaled(a.kp, lead.kp, "kp"), ki=scaled(a.ki, lead.ki, "ki"), kx=kx)

    return replace(spec, axes=tuple(moved(a) for a in spec.axes))


def require_valid(spec: ControllerSpec) -> ControllerSpec:
    """``spec`` itself when :func:`spec_problems` finds nothing, else a ConfigError listing all."""
    problems = spec_problems(spec)
    if problems:
        lines = [f"{'.'.join(path)}: {message}" for path, message in problems]
        raise ConfigError(f"controller spec {spec.name!r}: " + "; ".join(lines))
    return spec
