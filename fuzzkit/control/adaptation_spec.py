"""The ``adaptation:`` section of a controller spec: what adapts the scaling factors online.

The paper's sec. 3.2.4 sets the scaling factors ``Kp``, ``Ki``, ``Kx`` by trial and error for one
environment and points to factors that adapt while the task runs. Two modes
(``docs/controller.md``, "Adaptation"; the arithmetic is :mod:`fuzzkit.control.adaptation`):

* ``stiffness-scheduled``: an online estimate of the contact stiffness (recursive least squares
  with forgetting on the windowed increments ``df = k * du``, gated by an excitation threshold,
  bounded) picks a band, and the band's ``scale`` multiplies the output gain (``kx`` of a
  fuzzy-PI; ``kp`` and ``ki``, the output of eq. 9, of a PI). A band change waits a dwell time.
* ``self-tuning`` after Mudi and Pal (1999): the output gain multiplied each period by a gain
  ``alpha`` from a 7x7 fuzzy rule base on the normalised ``e`` and ``de``, mapped onto
  ``[alpha_min, alpha_max]``.

Stiffness is in N/mm (``_n_mm``), the unit the environments are quoted in.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

#: Adaptation modes.
MODES = ("none", "stiffness-scheduled", "self-tuning")
#: The longest estimator history the generated controller keeps (window + delay, periods).
MAX_HISTORY = 64

#: A logical position in a spec: the YAML keys leading to a value.
SpecPath = tuple[str, ...]


@dataclass(frozen=True, slots=True)
class Estimator:
    """The online stiffness estimate of one force-controlled axis.

    ``df = f_k - f_{k-W}`` (the filtered force, N) is regressed on ``du = u_{k-D} - u_{k-D-W}``
    (the correction, here in mm) with ``W = window_periods`` and ``D = delay_periods`` (the
    correction sent at period ``j`` shows in the force from ``j + D``: 1 without latency). The
    plant contract (``fuzzkit.plants.contract``) makes a positive correction raise the force, so
    ``df = +k * du`` (``de = -k * du``) with ``k > 0``. An update needs both ends of the window
    (a missing or rejected sample freezes the estimate until it leaves the window),
    ``|du| >= min_step_m`` and ``|df| >= min_force_n`` (the excitation threshold); the
    estimate is clamped to ``[k_min_n_mm, k_max_n_mm]`` and is ``initial_n_mm`` until the first
    update.

    The inner loop: the correction reaches the tool through the plant's motion loop, which
    ``fuzzkit stability`` identifies as two lags per period (``fuzzkit.analysis.inner_loop``):
    ``x_k = q*x_{k-1} + (1-q)*u_k``, ``m_k = a*m_{k-1} + (1-a)*g*x_k``. The estimator regresses
    ``df`` on the increments of ``m`` (the tool motion the corrections cause) instead of ``u``.
    ``inner_q = inner_a = 0``, ``inner_g = 1`` (the defaults): ``m = u``, no inner loop.
    """

    window_periods: int = 8
    delay_periods: int = 1
    forgetting: float = 0.9
    min_step_m: float = 2.0e-6
    min_force_n: float = 0.5
    initial_n_mm: float = 20.0
    k_min_n_mm: float = 1.0
    k_max_n_mm: float = 2000.0
    inner_q: float = 0.0
    inner_a: float = 0.0
    inner_g: float = 1.0


@dataclass(frozen=True, slots=True)
class Band:
    """One band of the schedule: estimates up to ``up_to_n_mm`` (None: the last, unbounded band)
    run with the output gain times ``scale``."""

    scale: float
    up_to_n_mm: float | None = None


@dataclass(frozen=True, slots=True)
class Adaptation:
    """The spec's ``adaptation:`` section (``mode`` none: fixed gains, nothing else is read).

    stiffness-scheduled: ``estimator``, ``bands`` (increasing ``up_to_n_mm``, the last without
    one) and ``dwell_s`` (the least time between two band changes). self-tuning: ``alpha_min``,
    ``alpha_max`` (the range alpha is mapped onto) and the normalisers of the rule base's inputs,
    ``error_n`` and ``change_n`` (N; None: a fuzzy-PI's own ``1/ki`` and ``1/kp``).
    """

    mode: str = "none"
    estimator: Estimator = field(default_factory=Estimator)
    bands: tuple[Band, ...] = ()
    dwell_s: float = 0.1
    alpha_min: float = 0.2
    alpha_max: float = 1.0
    error_n: float | None = None
    change_n: float | None = None
    #: stiffness-scheduled without bands: the factor is ``min(1, inverse_n_mm / k)`` of the
    #: estimate ``k`` (the 1/k schedule: ``k * factor`` constant above ``inverse_n_mm``)
    inverse_n_mm: float | None = None

    def inverse_factor(self, k_n_mm: float) -> float:
        """The 1/k schedule's factor at the estimate ``k_n_mm``."""
        if self.inverse_n_mm is None:
            raise ValueError("not a 1/k schedule (no inverse_n_mm)")
        return min(1.0, self.inverse_n_mm / k_n_mm)

    def band_of(self, k_n_mm: float) -> int:
        """The index of the band holding the estimate ``k_n_mm``."""
        for i, band in enumerate(self.bands):
            if band.up_to_n_mm is None or k_n_mm <= band.up_to_n_mm:
                return i
        return len(self.bands) - 1

    def safe_band(self) -> int:
        """The band until the estimate is trusted: the one of ``k_max``, the stiffest contact
        the estimator's range admits (-1 for a 1/k schedule: no bands)."""
        return self.band_of(self.estimator.k_max_n_mm)

    def floor_band(self) -> int:
        """The most conservative band (the smallest scale; the first of equal ones), for a
        contact stiffer than ``k_max``."""
        scales = [b.scale for b in self.bands]
        return scales.index(min(scales)) if scales else -1

    def dwell_periods(self, period_s: float) -> int:
        """The dwell time in whole periods (at least 1)."""
        return max(1, math.ceil(self.dwell_s / period_s - 1e-9))


NONE = Adaptation()


def _bad(value: float | None, low: float, high: float = math.inf, open_low: bool = True) -> bool:
    if value is None or not math.isfinite(value):
        return True
    return not ((value > low if open_low else value >= low) and value <= high)


def adaptation_problems(ad: Adaptation, kind: str, period_s: float) -> list[tuple[SpecPath, str]]:
    """Every semantic problem of the adaptation section, with the YAML path at fault."""
    out: list[tuple[SpecPath, str]] = []
    base: SpecPath = ("adaptation",)
    if ad.mode not in MODES:
        out.append(
            ((*base, "mode"), f"unknown adaptation {ad.mode!r}; expected {', '.join(MODES)}")
        )
        return out
    if ad.mode == "stiffness-scheduled":
        out += _estimator_problems(ad.estimator)
        if ad.inverse_n_mm is None:
            out += _band_problems(ad)
        elif _bad(ad.inverse_n_mm, 0.0) or ad.bands:
            out.append(
                (
                    (*base, "inverse_n_mm"),
                    f"inverse_n_mm must be a finite number > 0, without bands (got "
                    f"{ad.inverse_n_mm!r}, {len(ad.bands)} bands)",
                )
            )
        if _bad(ad.dwell_s, 0.0, open_low=False):
            out.append(
                ((*base, "dwell_s"), f"dwell_s must be a finite number >= 0 (got {ad.dwell_s!r})")
            )
    if ad.mode == "self-tuning":
        if _bad(ad.alpha_min, 0.0, 1.0, open_low=False) or _bad(ad.alpha_max, 0.0, 1.0):
            out.append(
                (
                    (*base, "alpha"),
                    f"alpha needs 0 <= min <= max <= 1 and max > 0 (got {ad.alpha_min!r}, "
                    f"{ad.alpha_max!r})",
                )
            )
        elif ad.alpha_min > ad.alpha_max:
            out.append(
                ((*base, "alpha"), f"alpha min {ad.alpha_min:g} is above max {ad.alpha_max:g}")
            )
        for key, value in (("error_n", ad.error_n), ("change_n", ad.change_n)):
            if value is None:
                if kind == "pi":
                    out.append(
                        (
                            (*base, key),
                            f"a pi needs adaptation.{key} (N): the normaliser of the rule "
                            "base's input",
                        )
                    )
            elif _bad(value, 0.0):
                out.append(((*base, key), f"{key} must be a finite number > 0 (got {value!r})"))
    return out


def _estimator_problems(est: Estimator) -> list[tuple[SpecPath, str]]:
    out: list[tuple[SpecPath, str]] = []
    base: SpecPath = ("adaptation", "estimator")
    if est.window_periods < 1 or est.delay_periods < 1:
        out.append((base, "window_periods and delay_periods must be integers >= 1"))
    elif est.window_periods + est.delay_periods > MAX_HISTORY:
        out.append(
            (
                (*base, "window_periods"),
                f"window_periods + delay_periods must be at most {MAX_HISTORY} (got "
                f"{est.window_periods + est.delay_periods}): the history is a fixed array",
            )
        )
    if _bad(est.forgetting, 0.0, 1.0):
        out.append(
            ((*base, "forgetting"), f"forgetting must be in (0, 1] (got {est.forgetting!r})")
        )
    for key, value in (("q", est.inner_q), ("a", est.inner_a)):
        if _bad(value, 0.0, 1.0, open_low=False) or value >= 1.0:
            out.append(
                (
                    (*base, "inner_loop", key),
                    f"inner_loop.{key} (a lag's pole) must be in [0, 1) (got {value!r})",
                )
            )
    if _bad(est.inner_g, 0.0):
        out.append(
            (
                (*base, "inner_loop", "g"),
                f"inner_loop.g must be a finite number > 0 (got {est.inner_g!r})",
            )
        )
    for key in ("min_step_m", "min_force_n"):
        value = getattr(est, key)
        if _bad(value, 0.0):
            out.append(((*base, key), f"{key} must be a finite number > 0 (got {value!r})"))
    if _bad(est.k_min_n_mm, 0.0) or _bad(est.k_max_n_mm, 0.0) or est.k_min_n_mm >= est.k_max_n_mm:
        out.append(
            (
                (*base, "range_n_mm"),
                f"range_n_mm needs 0 < k_min < k_max, finite (got [{est.k_min_n_mm!r}, "
                f"{est.k_max_n_mm!r}])",
            )
        )
    elif _bad(est.initial_n_mm, 0.0) or not est.k_min_n_mm <= est.initial_n_mm <= est.k_max_n_mm:
        out.append(
            (
                (*base, "initial_n_mm"),
                f"initial_n_mm must lie in range_n_mm [{est.k_min_n_mm:g}, {est.k_max_n_mm:g}] "
                f"(got {est.initial_n_mm!r})",
            )
        )
    return out


def _band_problems(ad: Adaptation) -> list[tuple[SpecPath, str]]:
    out: list[tuple[SpecPath, str]] = []
    base: SpecPath = ("adaptation", "bands")
    if not ad.bands:
        return [(base, "a stiffness schedule needs at least one band")]
    last = -math.inf
    for i, band in enumerate(ad.bands):
        path = (*base, str(i))
        if _bad(band.scale, 0.0):
            out.append(
                ((*path, "scale"), f"scale must be a finite number > 0 (got {band.scale!r})")
            )
        final = i == len(ad.bands) - 1
        if band.up_to_n_mm is None:
            if not final:
                out.append((path, "only the last band may leave out up_to_n_mm"))
            continue
        if final:
            out.append(
                (
                    (*path, "up_to_n_mm"),
                    "the last band takes every stiffness above: leave out up_to_n_mm",
                )
            )
        elif _bad(band.up_to_n_mm, 0.0) or band.up_to_n_mm <= last:
            out.append(
                (
                    (*path, "up_to_n_mm"),
                    f"up_to_n_mm must be finite, > 0 and increasing (got {band.up_to_n_mm!r})",
                )
            )
        else:
            last = band.up_to_n_mm
    return out


#: The kit's default stiffness schedule on the shipped gains (``--controller adaptive-pi`` and
#: ``adaptive-fuzzy-pi``; ``docs/examples/controller_adaptive.yaml`` spells it out): the band
#: scale keeps ``k * scale`` of the shipped gains, tuned near 10 N/mm, within a factor of about
#: 3 of its value there, from 1 to 2000 N/mm.
DEFAULT_BANDS = (Band(0.5, 30.0), Band(0.2, 150.0), Band(0.05, 600.0), Band(0.02))
DEFAULT_ESTIMATOR = Estimator(
    window_periods=8,
    delay_periods=1,
    forgetting=0.97,
    min_step_m=2.0e-6,
    min_force_n=0.2,
    initial_n_mm=300.0,
    k_min_n_mm=1.0,
    k_max_n_mm=2000.0,
)


#: The inner loops ``fuzzkit stability`` identifies (``fuzzkit.analysis.inner_loop.identify``),
#: the middle of each identified range rounded to 3 decimals, as ``(inner_q, inner_a,
#: inner_g)`` for a spec's ``estimator.inner_loop: {q, a, g}`` (docs/controller.md).
IDENTIFIED_INNER_LOOPS = {"planar": (0.213, 0.765, 0.986), "arm6": (0.0, 0.607, 1.0)}


def default_schedule(latency_periods: int = 0) -> Adaptation:
    """The default stiffness schedule for a loop with ``latency_periods`` (sensor + command):
    the estimator's delay is ``1 + latency_periods``."""
    est = replace(DEFAULT_ESTIMATOR, delay_periods=1 + latency_periods)
    return Adaptation("stiffness-scheduled", est, DEFAULT_BANDS, dwell_s=0.1)
