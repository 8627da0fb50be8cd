"""Where the fuzzy-PI's loop can rest, found from its surface before anything is certified.

The incremental fuzzy-PI adds ``du = Kx * F(Ki*e, Kp*de)`` every period. At rest the change of
error is 0 and the correction stops moving, so the loop can rest only where
``F(Ki*e, 0) = 0``: the **zero set** of the surface on the line ``de = 0``. The force then
settles at ``f = f_d - e`` (``e = f_d - f``), which is the set point only when ``x = 0`` is
that zero, ``F(0, 0) = 0``. A rule base with ``F(0, 0) = 0.2`` (say ``du = e + de + 0.2``) rests
at ``Ki*e = -0.2``: with ``Ki = 0.05`` per N the force settles 4 N above the set point, and a
certificate of "settles at the set point" would be false.

The zero set is found on the line ``y = 0`` of the scaled inputs: the surface is evaluated at
:data:`SAMPLES` points of [-1, 1] (0 among them, and any breakpoints given), a sample within
rounding of 0 (:data:`ZERO_TOLERANCE` of the largest ``|F|`` on the line) is a zero, and every
sign change between two samples is refined by Brent's method. Zeros closer together than the
sample step (1/1024 of the range) may be seen as one or none; the value at the origin is
exact.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]

#: Samples of ``F(x, 0)`` on [-1, 1] (odd: 0 is one of them).
SAMPLES = 2049
#: Relative (to the largest ``|F(x, 0)|``, at least 1) size below which ``F`` counts as 0.
ZERO_TOLERANCE = 1e-12


@dataclass(frozen=True, slots=True)
class ZeroSet:
    """The zeros of ``F(x, 0)`` on [-1, 1], in the scaled error ``x = Ki*e``.

    ``f00``: ``F(0, 0)``. ``intervals``: the zero set as closed intervals (a lone zero is
    ``(x, x)``), sorted. ``nearest``: the zero interval closest to ``x = 0`` (None when the
    surface has no zero on the line: the correction keeps growing, the loop has no rest).
    """

    f00: float
    intervals: tuple[tuple[float, float], ...]

    @property
    def nearest(self) -> tuple[float, float] | None:
        """The zero interval nearest the origin."""
        if not self.intervals:
            return None
        return min(self.intervals, key=lambda iv: abs(_closest_to_origin(iv)))

    @property
    def rest_point(self) -> float | None:
        """The rest point nearest the origin (the model is linearised around it)."""
        near = self.nearest
        return None if near is None else _closest_to_origin(near)

    @property
    def at_origin(self) -> bool:
        """``x = 0`` is a lone zero: the loop rests at the set point and only there nearby."""
        near = self.nearest
        return near is not None and near == (0.0, 0.0)


def _closest_to_origin(interval: tuple[float, float]) -> float:
    lo, hi = interval
    return 0.0 if lo <= 0.0 <= hi else (lo if abs(lo) < abs(hi) else hi)


def zero_set(
    surface: Callable[[FloatArray], FloatArray], breakpoints: Sequence[float] = ()
) -> ZeroSet:
    """The zero set of ``x -> surface(x)`` (``F(x, 0)``, vectorised) on [-1, 1]."""
    from scipy.optimize import brentq

    xs = np.union1d(np.linspace(-1.0, 1.0, SAMPLES), np.clip(np.asarray(breakpoints), -1.0, 1.0))
    xs = np.union1d(xs, [0.0])
    fs = np.asarray(surface(xs), dtype=np.float64)
    if not np.all(np.isfinite(fs)):
        bad = float(xs[~np.isfinite(fs)][0])
        raise ValueError(f"the surface is not finite at e = {bad:g}, de = 0")
    tol = ZERO_TOLERANCE * max(1.0, float(np.max(np.abs(fs))))
    zero = np.abs(fs) <= tol
    fs = np.where(zero, 0.0, fs)
    intervals: list[tuple[float, float]] = []
    i = 0
    while i < xs.size:
        if zero[i]:
            j = i
            while j + 1 < xs.size and zero[j + 1]:
                j += 1
            intervals.append((float(xs[i]), float(xs[j])))
            i = j + 1
            continue
        if i + 1 < xs.size and not zero[i + 1] and fs[i] * fs[i + 1] < 0.0:
            lo, hi = float(xs[i]), float(xs[i + 1])
            root = float(
                brentq(lambda x: float(surface(np.array([x]))[0]), lo, hi, xtol=1e-15, rtol=1e-15)
            )
            intervals.append((root, root))
        i += 1
    f00 = float(fs[np.searchsorted(xs, 0.0)])
    return ZeroSet(f00, tuple(intervals))


@dataclass(frozen=True, slots=True)
class Equilibrium:
    """The loop's rest point for one set of gains, in newtons.

    ``offset_n``: the force at rest minus the set point (NaN: no rest point). ``band_n``: for a
    zero interval (a dead band of the surface), the forces at rest span
    ``set point + offset_n + [band_n[0], band_n[1]]``. ``at_setpoint``: the set point is the
    loop's only rest point nearby, so a certificate may say "settles at the set point".
    """

    f00: float
    x_eq: float
    offset_n: float
    band_n: tuple[float, float]
    at_setpoint: bool
    why: str

    def as_dict(self) -> dict[str, object]:
        """JSON form (NaN becomes null)."""
        return {
            "surface_at_origin": self.f00,
            "scaled_error_at_rest": _finite(self.x_eq),
            "offset_n": _finite(self.offset_n),
            "rest_band_n": [_finite(b) for b in self.band_n],
            "at_setpoint": self.at_setpoint,
            "why": self.why,
        }


def _finite(x: float) -> float | None:
    return x if math.isfinite(x) else None


def pi_equilibrium() -> Equilibrium:
    """The PI's rest point: ``du = Kp*de + Ki*e`` is 0 at rest only at ``e = 0`` (``Ki > 0``)."""
    return Equilibrium(0.0, 0.0, 0.0, (0.0, 0.0), True, "PI: at rest du = Ki*e, zero only at e = 0")


def fuzzy_equilibrium(zeros: ZeroSet, ki: float, setpoint_n: float) -> Equilibrium:
    """The fuzzy-PI's rest point for the error gain ``ki`` (per N): where ``F(ki*e, 0) = 0``.

    The rest point nearest the set point is the one the certificate's model is linearised
    around; a zero interval (a dead band) makes every force in it a rest point.
    """
    near = zeros.nearest
    if near is None:
        sign = "above" if zeros.f00 > 0.0 else "below"
        return Equilibrium(
            zeros.f00,
            math.nan,
            math.nan,
            (math.nan, math.nan),
            False,
            f"F(e, 0) stays {sign} 0 on the whole universe (F(0, 0) = {zeros.f00:.4g}): the "
            "correction never stops moving, the loop has no rest point",
        )
    lo, hi = near
    x_eq = _closest_to_origin(near)
    # e = x / ki at rest, force = set point - e
    offset = -x_eq / ki
    band = (0.0 - (hi - x_eq) / ki, 0.0 - (lo - x_eq) / ki)  # 0.0 -: no negative zero
    if zeros.at_origin:
        return Equilibrium(
            zeros.f00, 0.0, 0.0, (0.0, 0.0), True, "F(0, 0) = 0: the loop rests at the set point"
        )
    force = setpoint_n + offset
    if lo < hi:
        why = (
            f"F(e, 0) = 0 for Ki*e in [{lo:.4g}, {hi:.4g}]: the loop can rest anywhere with the "
            f"force in [{force + band[0]:.4g}, {force + band[1]:.4g}] N, not only at the set "
            f"point {setpoint_n:g} N"
        )
    else:
        side = "above" if offset > 0.0 else "below"
        why = (
            f"F(0, 0) = {zeros.f00:.4g}, not 0: the loop rests where F(Ki*e, 0) = 0, at "
            f"Ki*e = {x_eq:.4g} (e = {x_eq / ki:.4g} N), so the force settles at {force:.4g} N, "
            f"{abs(offset):.4g} N {side} the set point {setpoint_n:g} N"
        )
    return Equilibrium(zeros.f00, x_eq, offset, band, False, why)
