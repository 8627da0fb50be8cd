"""Force controllers of the outer loop: incremental PI, fuzzy-PI and the hybrid force/motion law.

Signs and units
---------------
* ``e = setpoint - measured`` (eq. 5, newtons), ``de = e - e_previous`` (eq. 6, newtons per step).
* The controllers return the accumulated correction ``u`` (eq. 8, metres) along one task axis.
  A positive correction moves the tool *into* the surface and so increases the force
  (see ``fuzzkit.plants.contract``): the gains are positive.
* :class:`PI`: ``du = Kp*de + Ki*e`` (eq. 9); ``Kp``, ``Ki`` in metres per newton.
* :class:`FuzzyPI`: ``du = Kx * F(Ki*e, Kp*de)`` where ``F`` is the rule base's control surface on
  the normalised universe [-1, 1]: **Ki scales the error e, Kp scales the change of error de**
  (1/N each), and **Kx scales the output** (metres per step). Scaled inputs are clipped to
  [-1, 1] first, so ``|du| <= Kx * max|F|``: a fuzzy-PI has a built-in correction-rate limit.
  Near the origin a MacVicar-Whelan table behaves like ``F ~ a*e + b*de``, i.e. like a PI with
  ``Ki_pi ~ Kx*Ki*a`` and ``Kp_pi ~ Kx*Kp*b``.

Both accept ``u_min``/``u_max`` (clamping the accumulated correction is the anti-windup of the
incremental form) and an optional ``rate_limit`` (largest ``|du|`` per step). A NaN measurement
never becomes a correction: the step is skipped, ``u`` is held and ``faults`` is incremented.

Twins: this is the **reference** copy of the controller; the compiled loop's copy
(:mod:`fuzzkit.loop.compiled.period`) and the generated controller
(:mod:`fuzzkit.codegen.controller`) are tested against it (``tests/test_compiled_loop.py``,
``tests/test_controller_codegen.py``), so it stays a separate implementation on purpose.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any, Protocol, cast, runtime_checkable

import numpy as np
import numpy.typing as npt

from fuzzkit.control import status as st
from fuzzkit.control.adaptation import StiffnessSchedule
from fuzzkit.control.frontend import FrontEnd
from fuzzkit.errors import ConfigError

Vec = npt.NDArray[np.float64]

#: A control surface: ``(e_normalised, de_normalised) -> du_normalised`` on [-1, 1].
Surface = Callable[[float, float], float]


@runtime_checkable
class AxisController(Protocol):
    """One force controller along one task axis (PI, FuzzyPI or a generated module's class)."""

    def step(self, setpoint: float, measured: float) -> float:
        """Process one sample; return the accumulated correction u (m)."""
        ...

    def reset(self) -> None:
        """Forget the history: u = 0, no previous error."""
        ...


def saturated_sum_surface(e: float, de: float) -> float:
    """Reference surface ``clip(e + de, -1, 1)``: the continuous limit of the canonical
    MacVicar-Whelan table (``out = clamp(i_e + i_de, -3, 3)``). For tests and quick studies."""
    return min(max(e + de, -1.0), 1.0)


def engine_surface(engine: Any, e_name: str, de_name: str, out_name: str) -> Surface:
    """Wrap an inference engine (``fuzzkit.fuzzy.inference.Engine``) as a :data:`Surface`:
    ``(e, de) -> out`` with the rule base's own names for the error input, the change input and
    the output (:func:`fuzzkit.control.loop_rulebase.role_names`)."""
    order = tuple(getattr(engine, "input_names", ()))
    if order == (e_name, de_name) and hasattr(engine, "point_function"):
        return cast(Surface, engine.point_function(out_name))  # the fast per-sample path

    def surface(e: float, de: float) -> float:
        return float(engine.evaluate_point(**{e_name: e, de_name: de})[out_name])

    return surface


def lookup_table_surface(table: Any) -> Surface:
    """Wrap a ``fuzzkit.codegen.lookup_table.LookupTable`` (inputs e, de; output du) as a
    :data:`Surface`.

    Uses the table's reference interpolation, which reproduces the generated code's arithmetic.
    """

    def surface(e: float, de: float) -> float:
        return float(table.interpolate([e, de])[0])

    return surface


class _Incremental:
    """Shared state and limits of the incremental controllers (eq. 8)."""

    def __init__(self, u_min: float, u_max: float, rate_limit: float | None) -> None:
        if not u_min <= 0.0 <= u_max:
            raise ConfigError(
                f"output limits must satisfy u_min <= 0 <= u_max (got {u_min}, {u_max})"
            )
        if rate_limit is not None and not rate_limit > 0.0:
            raise ConfigError(f"rate_limit must be > 0 or None (got {rate_limit})")
        self.u_min, self.u_max, self.rate_limit = u_min, u_max, rate_limit
        #: Online adaptation: ``(e, de) -> s``, the factor of this period's increment
        #: (``fuzzkit.control.adaptation``); None: fixed gains.
        self.adapt: Callable[[float, float], float] | None = None
        self.reset()

    def reset(self) -> None:
        """Forget the history: u = 0, no previous error, zero fault count."""
        self.u = 0.0
        self.e = 0.0
        self.de = 0.0
        self.du = 0.0
        self.faults = 0
        self.saturated = False  # a limit (|du| or u) acted in the last step
        self._e_prev: float | None = None

    def _increment(self, e: float, de: float) -> float:
        raise NotImplementedError

    def step(self, setpoint: float, measured: float) -> float:
        """Process one sample and return the accumulated correction ``u`` (m).

        A NaN/inf ``measured`` is a sensor fault: u is held, ``faults`` counts it, and the next
        valid sample's ``de`` is taken against the last valid error.
        """
        self.saturated = False
        if not math.isfinite(measured) or not math.isfinite(setpoint):
            self.faults += 1
            self.du = 0.0
            return self.u
        e = setpoint - measured
        de = 0.0 if self._e_prev is None else e - self._e_prev
        self._e_prev = e
        du = self._increment(e, de)
        if self.adapt is not None:
            du = self.adapt(e, de) * du
        if not math.isfinite(du):  # a surface that answers NaN must not move the robot
            self.faults += 1
            du = 0.0
        if self.rate_limit is not None and abs(du) > self.rate_limit:
            du = min(max(du, -self.rate_limit), self.rate_limit)
            self.saturated = True
        u = min(max(self.u + du, self.u_min), self.u_max)
        self.saturated |= u != self.u + du
        self.e, self.de, self.du, self.u = e, de, u - self.u, u
        return u


class PI(_Incremental):
    """Incremental PI force controller, eqs. 8-9: ``du = Kp*de + Ki*e``, ``u += du``.

    Parameters
    ----------
    kp, ki : gains in metres per newton (``kp`` on the change of error, ``ki`` on the error).
    u_min, u_max : limits of the accumulated correction (m); clamping is the anti-windup.
    rate_limit : optional largest ``|du|`` per step (m).

    Examples
    --------
    >>> pi = PI(kp=4e-5, ki=1e-5)
    >>> round(pi.step(10.0, 0.0) * 1e6, 3)  # first step: de = 0, du = Ki*e
    100.0
    """

    def __init__(
        self,
        kp: float,
        ki: float,
        u_min: float = -math.inf,
        u_max: float = math.inf,
        rate_limit: float | None = None,
    ) -> None:
        if not (math.isfinite(kp) and math.isfinite(ki)) or kp < 0.0 or ki < 0.0:
            raise ConfigError(f"PI gains must be finite and >= 0 (got kp={kp}, ki={ki})")
        self.kp, self.ki = kp, ki
        super().__init__(u_min, u_max, rate_limit)

    def _increment(self, e: float, de: float) -> float:
        return self.kp * de + self.ki * e


class FuzzyPI(_Incremental):
    """Fuzzy-PI force controller: ``du = Kx * F(clip(Ki*e), clip(Kp*de))``, ``u += du``.

    ``surface`` is any callable ``(e, de) -> du`` on the normalised universe: the exact engine
    (:func:`engine_surface`), a lookup table, a generated module's function, or
    :func:`saturated_sum_surface`.

    Parameters
    ----------
    surface : the control surface F.
    kp : scale of the change of error ``de`` (1/N).
    ki : scale of the error ``e`` (1/N).
    kx : scale of the output (m per step).
    u_min, u_max, rate_limit : as for :class:`PI`.
    """

    def __init__(
        self,
        surface: Surface,
        kp: float,
        ki: float,
        kx: float,
        u_min: float = -math.inf,
        u_max: float = math.inf,
        rate_limit: float | None = None,
    ) -> None:
        gains = (kp, ki, kx)
        if not all(math.isfinite(g) and g > 0.0 for g in gains):
            raise ConfigError(f"fuzzy-PI scaling factors must be finite and > 0 (got {gains})")
        self.surface, self.kp, self.ki, self.kx = surface, kp, ki, kx
        super().__init__(u_min, u_max, rate_limit)

    def _increment(self, e: float, de: float) -> float:
        en = min(max(self.ki * e, -1.0), 1.0)
        den = min(max(self.kp * de, -1.0), 1.0)
        return self.kx * float(self.surface(en, den))


class HybridForceController:
    """The outer loop of the hybrid force/motion controller (paper, sec. 3).

    One :class:`AxisController` per task axis (x, y, z), a diagonal selection matrix ``S``
    (``selection[i]`` is 1 for a force-controlled axis, 0 for a motion-only one), per-axis set
    points, and four safeguards:

    * **spike gate**: a sample that differs from the last accepted one by more than
      ``spike_gate_n`` on any axis (default: half of ``force_limit_n``) is rejected like a
      NaN (correction held, ``faults`` and ``rejected`` count it), unless ``spike_confirm``
      samples in a row have been rejected: then the new level is accepted. An isolated sensor
      spike never reaches the axis controllers, the engagement or the trip logic; a real force
      step faster than the gate is seen ``spike_confirm`` periods late;
    * **engagement** (debounced): with ``engage_threshold_n`` set, the loop stays idle (zero
      correction) until ``engage_samples`` consecutive valid samples each have a force above it
      on some axis ("on contact the controller takes over"); an invalid sample restarts the
      count;
    * **force safety limit**: when any force exceeds ``force_limit_n`` on ``trip_samples``
      consecutive samples, the last of them accepted by the gate (or on ``spike_confirm``
      consecutive samples, gated or not), the controller latches ``tripped``, stops
      correcting, and backs off along the measured force direction by ``backoff_m`` at
      ``backoff_speed_m_s``; only :meth:`reset` clears it;
    * **sensor faults**: a sample with NaN/inf on a force-controlled axis (or ``None``) holds
      the correction and increments ``faults``.

    An optional ``front_end`` (:class:`~fuzzkit.control.frontend.FrontEnd`: tare, gravity
    compensation, low-pass) turns each raw sample into the force the logic above sees: the
    spike gate and the trip see the compensated sample, engagement and the axis controllers
    the filtered one (``docs/controller.md`` gives the order).

    :meth:`step` returns the task-frame correction ``S*u + backoff`` (m); ``status`` then holds
    the step's bits (:mod:`fuzzkit.control.status`).
    """

    def __init__(
        self,
        controllers: Sequence[AxisController | None],
        setpoints: Sequence[float],
        period_s: float,
        force_limit_n: float = 50.0,
        engage_threshold_n: float | None = None,
        trip_samples: int = 2,
        backoff_m: float = 0.005,
        backoff_speed_m_s: float = 0.02,
        engage_samples: int = 3,
        spike_gate_n: float | None = None,
        spike_confirm: int = 4,
        front_end: FrontEnd | None = None,
        schedules: Sequence[StiffnessSchedule | None] | None = None,
    ) -> None:
        if len(controllers) != 3 or len(setpoints) != 3:
            raise ConfigError(
                "HybridForceController needs 3 controllers and 3 set points (x, y, z)"
            )
        if not force_limit_n > 0.0:
            raise ConfigError(f"force_limit_n must be > 0 (got {force_limit_n})")
        if trip_samples < 1:
            raise ConfigError(f"trip_samples must be >= 1 (got {trip_samples})")
        if engage_samples < 1:
            raise ConfigError(f"engage_samples must be >= 1 (got {engage_samples})")
        if spike_confirm < 1:
            raise ConfigError(f"spike_confirm must be >= 1 (got {spike_confirm})")
        if spike_gate_n is not None and not spike_gate_n > 0.0:
            raise ConfigError(f"spike_gate_n must be > 0 or None (got {spike_gate_n})")
        self.controllers = list(controllers)
        self.selection = np.array([0.0 if c is None else 1.0 for c in controllers])
        self.setpoints = np.asarray(setpoints, dtype=np.float64)
        self.period_s = period_s
        self.force_limit_n = force_limit_n
        self.engage_threshold_n = engage_threshold_n
        self.trip_samples = trip_samples
        self.backoff_m = backoff_m
        self.backoff_speed_m_s = backoff_speed_m_s
        self.engage_samples = engage_samples
        self.spike_gate_n = 0.5 * force_limit_n if spike_gate_n is None else spike_gate_n
        self.spike_confirm = spike_confirm
        self.front_end = front_end
        self.schedules = list(schedules) if schedules is not None else [None, None, None]
        if len(self.schedules) != 3:
            raise ConfigError("HybridForceController needs 3 schedules (x, y, z) or None")
        self.reset()

    def reset(self) -> None:
        """Clear every axis controller, the engagement, the trip latch, the fault count and the
        front end (whose tare starts again)."""
        for c in self.controllers:
            if c is not None:
                c.reset()
        if self.front_end is not None:
            self.front_end.reset()
        for sched in self.schedules:
            if sched is not None:
                sched.reset()
        self.status = 0
        self.u = np.zeros(3)
        self.e = np.zeros(3)
        self.de = np.zeros(3)
        self.du = np.zeros(3)
        self.faults = 0
        self.rejected = 0
        self.engaged = self.engage_threshold_n is None
        self._above = 0
        self._accepted: Vec | None = None
        self._rejected_run = 0
        self.tripped = False
        self.trip_time_s: float | None = None
        self._over = 0
        self._backoff = np.zeros(3)
        self._backoff_dir = np.zeros(3)
        self._e_last: Vec | None = None
        self._t = 0.0

    def request_tare(self) -> None:
        """Take the next valid samples as a new tare (front end with tare only; free air)."""
        if self.front_end is not None:
            self.front_end.request_tare()

    def step(self, force: Vec | None, rotation: Vec | None = None) -> Vec:
        """Consume one raw force sample and return the correction (m, task frame).

        ``force``: the sensor's reading (N, task frame; NaN entries or None: missing).
        ``rotation``: the tool's rotation, world-from-sensor (3x3), needed when the front end
        compensates gravity (without it the sample is missing).
        """
        self._t += self.period_s
        self.du = np.zeros(3)
        self.status = 0
        fe = self.front_end
        no_rotation = rotation is None or not bool(np.all(np.isfinite(rotation)))
        if fe is not None and fe.needs_rotation and no_rotation:
            force = None  # the tool's weight is unknown: the sample cannot be used
        valid = force is not None and bool(np.all(np.isfinite(force[self.selection > 0])))
        if force is None or not valid:
            return self._missing()
        if fe is not None and fe.taring:
            return self._tare(fe, force, rotation)
        if fe is not None:
            f = fe.compensate(force, rotation)
        else:
            f = np.where(np.isfinite(force), force, 0.0)
        plausible = self._plausible(f)
        if not self.tripped:
            # The trip sees every finite sample, gated or not: a real force that rises faster
            # than the gate still trips, after spike_confirm samples at the latest.
            self._over = self._over + 1 if float(np.max(np.abs(f))) > self.force_limit_n else 0
            if self._over >= (self.trip_samples if plausible else self.spike_confirm):
                self._trip(f)
        if not plausible and not self.tripped:
            self._observe(None)
            self.faults += 1
            self.rejected += 1
            self._above = 0
            self.status |= st.REJECTED | st.HELD
            return self._output()
        if self.tripped:
            step = self.backoff_speed_m_s * self.period_s
            if float(np.linalg.norm(self._backoff)) < self.backoff_m:
                self._backoff = self._backoff + step * self._backoff_dir
                self.status |= st.RETREATING
            return self._output()
        if fe is not None:
            f = fe.filter(f)
        if not self.engaged:
            thr = self.engage_threshold_n if self.engage_threshold_n is not None else 0.0
            self._above = self._above + 1 if float(np.max(np.abs(f))) > thr else 0
            if self._above < self.engage_samples:
                return self._output()
            self.engaged = True
        self._observe(f)
        for i, c in enumerate(self.controllers):
            if c is None:
                continue
            before = self.u[i]
            self.u[i] = c.step(float(self.setpoints[i]), float(f[i]))
            self.du[i] = self.u[i] - before
            self.e[i] = self.setpoints[i] - f[i]
            if getattr(c, "saturated", False):
                self.status |= st.SATURATED
        self.de = self.e - self._e_last if self._e_last is not None else np.zeros(3)
        self._e_last = self.e.copy()
        return self._output()

    def wait(self) -> Vec:
        """A period in which no sample can have arrived yet (at start-up, while the sensor's
        latency queue still holds no measurement): the output is held, as for a missing sample,
        but it is not counted as a sensor fault."""
        self._t += self.period_s
        self.du = np.zeros(3)
        self.status = st.HELD
        self._above = 0
        if self.front_end is not None and self.front_end.taring:
            self.status |= st.TARING
        return self._output()

    def _tare(self, fe: FrontEnd, force: Vec, rotation: Vec | None) -> Vec:
        """One tare sample: the spike gate keeps spikes out of the bias (a level confirmed
        after ``spike_confirm`` rejections restarts the tare: what came before was the
        outlier), the correction is held."""
        if not bool(np.all(np.isfinite(force))):
            return self._missing()
        self._observe(None)
        confirmed = self._accepted is not None and self._rejected_run >= self.spike_confirm
        if not self._plausible(force - fe.weight(rotation)):
            self.faults += 1
            self.rejected += 1
            self.status |= st.TARING | st.HELD | st.REJECTED
            return self._output()
        if confirmed:
            fe.request_tare()
        if fe.tare(force, rotation):
            self._accepted = None  # the bias moved: the gate starts afresh
            self._rejected_run = 0
        self.status |= st.TARING | st.HELD
        return self._output()

    def _missing(self) -> Vec:
        """A sample that cannot be used: hold, count it, restart the engagement count."""
        self._observe(None)
        self.faults += 1
        self._above = 0
        self.status |= st.HELD
        if self.front_end is not None and self.front_end.taring:
            self.status |= st.TARING
        return self._output()

    def _observe(self, f: Vec | None) -> None:
        """Feed each stiffness schedule one engaged, untripped period: the force its axis
        controller sees (None: the sample is held) and the correction before the step."""
        if not self.engaged or self.tripped:
            return
        for i, sched in enumerate(self.schedules):
            if sched is not None:
                sched.observe(math.nan if f is None else float(f[i]), float(self.u[i]))

    @property
    def stiffness_n_mm(self) -> Vec:
        """The stiffness estimate per axis (N/mm; NaN without a schedule)."""
        return np.array([math.nan if s is None else s.k for s in self.schedules])

    @property
    def gain_scale(self) -> Vec:
        """The factor of the output gain per axis in the last step (1 for fixed gains)."""
        out = np.ones(3)
        for i, c in enumerate(self.controllers):
            adapt = getattr(c, "adapt", None)
            if adapt is not None:
                out[i] = float(getattr(adapt, "last", 1.0))
        return out

    def _plausible(self, f: Vec) -> bool:
        """Spike gate: accept ``f`` unless it jumps past the gate from the last accepted sample
        (a run of ``spike_confirm`` rejections means the level really changed: accept it)."""
        if (
            self._accepted is not None
            and self._rejected_run < self.spike_confirm
            and float(np.max(np.abs(f - self._accepted))) > self.spike_gate_n
        ):
            self._rejected_run += 1
            return False
        self._accepted = f.copy()
        self._rejected_run = 0
        return True

    def _trip(self, f: Vec) -> None:
        self.tripped = True
        self.trip_time_s = self._t
        norm = float(np.linalg.norm(f))
        # Retreat against the force the tool exerts: away from whatever it is pressing on.
        self._backoff_dir = -f / norm if norm > 0.0 else np.zeros(3)

    def _output(self) -> Vec:
        if self.engaged:
            self.status |= st.ENGAGED
        if self.tripped:
            self.status |= st.TRIPPED
        for sched in self.schedules:
            if sched is not None:
                self.status |= sched.status
        return self.selection * self.u + self._backoff


def make_axis_controllers(
    kind: str,
    selection: Sequence[bool],
    gains: Mapping[str, float],
    surface: Surface | None = None,
) -> list[AxisController | None]:
    """Build one controller per selected axis from a gain mapping.

    ``kind`` is ``"pi"`` (gains ``kp``, ``ki``) or ``"fuzzy-pi"`` (gains ``kp``, ``ki``, ``kx``
    and a ``surface``); both accept optional ``u_min``, ``u_max``, ``rate_limit``.
    """
    limits: dict[str, Any] = {
        "u_min": gains.get("u_min", -math.inf),
        "u_max": gains.get("u_max", math.inf),
        "rate_limit": gains.get("rate_limit"),
    }
    out: list[AxisController | None] = []
    for sel in selection:
        if not sel:
            out.append(None)
        elif kind == "pi":
            out.append(PI(gains["kp"], gains["ki"], **limits))
        elif kind == "fuzzy-pi":
            if surface is None:
                raise ConfigError("fuzzy-pi needs a control surface (a rule base)")
            out.append(FuzzyPI(surface, gains["kp"], gains["ki"], gains["kx"], **limits))
        else:
            raise ConfigError(f"unknown controller {kind!r} (expected pi or fuzzy-pi)")
    return out
