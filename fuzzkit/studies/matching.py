"""Small-signal-matched gains: a fuzzy-PI with the same gain as a PI for small errors.

Why: near the origin a fuzzy-PI behaves like ``du ~ Kx * (s_e * Ki * e + s_de * Kp * de)``,
where ``s_e = dF/de`` and ``s_de = dF/dde`` are the control surface's slopes at the origin
(normalised units). A fair PI vs fuzzy-PI comparison gives both controllers the same
small-signal gain, so that any difference comes from the fuzzy surface's *shape*, not from a
hidden gain factor. The slopes are *measured* from the surface, never assumed: the centroid
MacVicar-Whelan surface has slope 1.5 at the origin (not 1), and bends quickly
(``F(0.02, 0) = 0.0278``, a secant slope of 1.39), so "the table is the saturated sum, so the
slope is 1" is wrong by 50 %.

What matching cannot do: the min/centroid surface is not differentiable at the origin. Its
partial slopes are 1.5 along each axis and ``F ~ 1.5 (x + y)`` while ``e`` and ``de`` have
opposite signs (the error shrinking), but while they have the same sign (the error growing)
the rule ``(PS, PS) -> PM`` fires too and ``F ~ 1.5 max(x, y) + 2.5 min(x, y)`` (slope 4 along
the diagonal). Matched gains equalise the PI and the fuzzy-PI on the axes and while the error
shrinks; while it grows, the fuzzy-PI has up to 4/3 of the PI's gain: that is part of the
surface's shape, which is what the comparison is meant to expose.

Matching rule (:func:`matched_fuzzy_gains`): keep the fuzzy-PI's ``Ki`` (it sets the error's
full scale, ``1/Ki`` newtons, i.e. where the surface saturates) and solve the other two
scaling factors from ``Kx * Ki * s_e = ki_pi`` and ``Kx * Kp * s_de = kp_pi``. A slope that is
zero (a rule base whose output does not depend on that input near the origin, such as the
paper's Table I as printed along ``e``) cannot be matched: the gain stays at its reference
value and the result says so.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

from fuzzkit.control.controllers import Surface
from fuzzkit.control.names import GAIN_KEYS
from fuzzkit.errors import ConfigError
from fuzzkit.studies.experiments import DEFAULT_GAINS

#: Half-width of the symmetric difference, normalised units. The centroid surface is not
#: differentiable twice at the origin (``F(e, 0) ~ 1.5 e - 6 e |e|`` for MacVicar-Whelan), so
#: the symmetric difference is off by about ``6 h`` relative: 6e-6 here, while round-off of
#: the engine (~1e-15 of F) adds ~1e-9.
SLOPE_STEP = 1.0e-6

#: Slopes below this are taken as zero: the surface does not respond to that input.
ZERO_SLOPE = 1.0e-6


@dataclass(frozen=True, slots=True)
class SurfaceSlopes:
    """The control surface's slopes at the origin (normalised output per normalised input)."""

    e: float  # dF/de at (0, 0)
    de: float  # dF/dde at (0, 0)
    step: float  # the symmetric difference's half-width used


def measure_slopes(surface: Surface, step: float = SLOPE_STEP) -> SurfaceSlopes:
    """Measure ``dF/de`` and ``dF/dde`` at the origin by a symmetric difference.

    Parameters
    ----------
    surface : the control surface ``F(e, de)`` on the normalised universe (e.g.
        ``fuzzkit.control.controllers.engine_surface(Engine(rule_base))``).
    step : half-width of the difference (normalised units); small enough to stay in the
        origin's cell, where every shipped partition is piecewise linear.

    Raises
    ------
    ConfigError
        ``step`` not in (0, 0.1], or the surface answers a non-finite value near the origin.

    Examples
    --------
    >>> from fuzzkit.control.controllers import saturated_sum_surface
    >>> s = measure_slopes(saturated_sum_surface)
    >>> round(s.e, 9), round(s.de, 9)
    (1.0, 1.0)
    """
    if not (math.isfinite(step) and 0.0 < step <= 0.1):
        raise ConfigError(f"slope step must be in (0, 0.1] (got {step})")
    values = [
        surface(step, 0.0),
        surface(-step, 0.0),
        surface(0.0, step),
        surface(0.0, -step),
    ]
    if not all(math.isfinite(v) for v in values):
        raise ConfigError(
            f"the control surface answers non-finite values near the origin ({values})"
        )
    return SurfaceSlopes(
        e=(values[0] - values[1]) / (2.0 * step),
        de=(values[2] - values[3]) / (2.0 * step),
        step=step,
    )


def small_signal_gains(gains: Mapping[str, float], slopes: SurfaceSlopes) -> tuple[float, float]:
    """A fuzzy-PI's small-signal PI gains ``(kp, ki)`` in m/N: ``Kx * Kp * dF/dde`` and
    ``Kx * Ki * dF/de`` (module docstring); a slope below :data:`ZERO_SLOPE` counts as 0."""

    def slope(s: float) -> float:
        return s if abs(s) > ZERO_SLOPE else 0.0

    return gains["kx"] * gains["kp"] * slope(slopes.de), gains["kx"] * gains["ki"] * slope(slopes.e)


def small_signal_ratios(
    surface: Surface,
    fuzzy_gains: Mapping[str, float] | None = None,
    pi_gains: Mapping[str, float] | None = None,
) -> tuple[float, float]:
    """The fuzzy-PI's small-signal gains relative to the PI's: ``(proportional, integral)``.

    The fuzzy-PI runs ``surface`` with ``fuzzy_gains``, the PI ``pi_gains`` (defaults:
    ``DEFAULT_GAINS``). The default gains make the fuzzy-PI the PI exactly on the saturated-sum
    surface (``Kx * Kp = kp``, ``Kx * Ki = ki``, slopes 1), so with them the ratios are the
    rule base's slopes at the origin: 1.5 for ``macvicar_whelan``.
    """
    fz = {**DEFAULT_GAINS["fuzzy-pi"], **(fuzzy_gains or {})}
    pi = {**DEFAULT_GAINS["pi"], **(pi_gains or {})}
    kp, ki = small_signal_gains(fz, measure_slopes(surface))
    return kp / pi["kp"], ki / pi["ki"]


def has_small_signal_gain(slopes: SurfaceSlopes) -> bool:
    """Whether a surface with these slopes at the origin has a small-signal gain to match: a
    positive slope above :data:`ZERO_SLOPE` along e or de (``sugeno_pi``, which holds du = 0
    around the origin, has none)."""
    return slopes.e > ZERO_SLOPE or slopes.de > ZERO_SLOPE


@dataclass(frozen=True, slots=True)
class MatchedGains:
    """Fuzzy-PI gains matched to a PI, and how: which gains could not be matched and why."""

    gains: dict[str, float]  # complete fuzzy-PI gains (kp, ki, kx, limits)
    pi_gains: dict[str, float]  # the PI they were matched to
    slopes: SurfaceSlopes
    unmatched: tuple[str, ...]  # human-readable notes, empty when both gains match

    @property
    def small_signal(self) -> tuple[float, float]:
        """The fuzzy-PI's small-signal PI gains ``(kp, ki)`` in m/N (compare with the PI's)."""
        return small_signal_gains(self.gains, self.slopes)

    def describe(self) -> str:
        """One line for humans: the slopes and what was matched."""
        kp, ki = self.small_signal
        text = (
            f"matched to pi (kp={self.pi_gains['kp']:.4g}, ki={self.pi_gains['ki']:.4g} m/N) "
            f"through the surface's slopes at the origin dF/de={self.slopes.e:.4f}, "
            f"dF/dde={self.slopes.de:.4f}: small-signal kp={kp:.4g}, ki={ki:.4g} m/N"
        )
        return text + ("; " + "; ".join(self.unmatched) if self.unmatched else "")


def matched_fuzzy_gains(
    surface: Surface,
    pi_gains: Mapping[str, float] | None = None,
    fuzzy_gains: Mapping[str, float] | None = None,
) -> MatchedGains:
    """Fuzzy-PI gains whose small-signal gain equals ``pi_gains``' (module docstring: the rule).

    Parameters
    ----------
    surface : the fuzzy-PI's control surface.
    pi_gains : the PI to match (``kp``, ``ki`` in m/N); default ``DEFAULT_GAINS["pi"]``.
    fuzzy_gains : the fuzzy-PI's reference gains: ``ki`` is kept, the output limits are
        copied, and a gain that cannot be matched keeps its value here; default
        ``DEFAULT_GAINS["fuzzy-pi"]``.

    Returns
    -------
    :class:`MatchedGains`; ``Kx * Ki * s_e == ki_pi`` and ``Kx * Kp * s_de == kp_pi`` hold
    for every gain not listed in ``unmatched``.

    Raises
    ------
    ConfigError
        Missing or non-positive gains, or a surface with zero slope along both inputs.
    """
    pi = dict(DEFAULT_GAINS["pi"])
    pi.update(pi_gains or {})
    fz = dict(DEFAULT_GAINS["fuzzy-pi"])
    fz.update(fuzzy_gains or {})
    for name, g in (("pi", pi), ("fuzzy-pi", fz)):
        for k in GAIN_KEYS[name]:
            if not (math.isfinite(g[k]) and g[k] > 0.0):
                raise ConfigError(f"matching needs {name} {k} > 0 (got {g[k]!r})")
    slopes = measure_slopes(surface)
    has_e, has_de = slopes.e > ZERO_SLOPE, slopes.de > ZERO_SLOPE
    if not has_small_signal_gain(slopes):
        raise ConfigError(
            "the rule base has no small-signal gain along e or de (both slopes at the origin "
            f"are {slopes.e:.3g}, {slopes.de:.3g}): there is nothing to match"
        )
    out = dict(fz)
    notes: list[str] = []
    if has_e:
        out["kx"] = pi["ki"] / (fz["ki"] * slopes.e)
    else:
        notes.append(
            f"ki not matched: dF/de = {slopes.e:.3g} at the origin (no integral action for "
            f"small errors); kx={fz['kx']:.4g} and ki={fz['ki']:.4g} kept"
        )
    if has_de:
        out["kp"] = pi["kp"] / (out["kx"] * slopes.de)
    else:
        notes.append(
            f"kp not matched: dF/dde = {slopes.de:.3g} at the origin (no proportional action "
            f"for small errors); kp={fz['kp']:.4g} kept"
        )
    return MatchedGains(out, {k: pi[k] for k in GAIN_KEYS["pi"]}, slopes, tuple(notes))
