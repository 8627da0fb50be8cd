"""The inner motion loop's response from correction to tool position, identified on a plant.

Each plant (``planar``, ``arm6``) is driven in contact with the flat surface of the regulation
task (:mod:`fuzzkit.analysis.regulation`) by a pseudo-random binary correction along task z
around the indentation of the set point, one controller period at a time, and the tool's z is
recorded. A cascade of two first-order lags per period,

    x[k] = q * x[k-1] + (1 - q) * r[k]          (r[k]: the correction the plant receives)
    p[k] = a * p[k-1] + (1 - a) * g * x[k]

is fitted at several stiffnesses, minimising the free-run simulation error (scipy's
least_squares). arm6's joints are one exact first-order lag (``q`` fits to 0); the planar arm's
pymunk servo starts slower (an S-shaped step response) and needs the second pole. The fit error
is the free-run NRMSE (error RMS over the motion's standard deviation). The model the
certificate uses carries it as uncertainty: ``a`` and ``q`` over the range of the fits widened
by the largest NRMSE, ``g`` over the range of the fits times ``1 +- NRMSE``.

**Series compliance.** A servo that is a spring (MuJoCo's PD joints) gives way under the
contact force: held still, the tool reaches only ``s(k) = k_s / (k + k_s)`` of a commanded
indentation against a contact of stiffness ``k``, the servo's stiffness ``k_s`` in series with
the contact's. Each identification stiffness is therefore also pressed and held
(:func:`press_gain`), ``k_s`` fitted to those static gains (:func:`series_stiffness`), each
fit made on the motion divided by ``s(k)`` and the model's gain at a stiffness ``k`` is
``g * s(k)`` (:meth:`InnerLoop.g_at`). A plant whose stiffest press loses less than
:data:`SERIES_THRESHOLD` of the command has no series term (arm6 loses 0, the planar arm 0.4 %
at 1000 N/mm: inside its ``g`` interval).

**Local in stiffness, with a slow lag.** Where the servo is a spring, the contact changes the
inner loop's dynamics as well as its gain: MuJoCo's arm overshoots (velocity feed-forward,
joint inertia) and creeps back through its gear friction. Such a plant is identified at each
of :data:`LOCAL_ID_STIFFNESSES` with the fast lag's own gain ``h`` and a slow lag ``y[k] =
b y[k-1] + (1 - b) (g - h) x[k]`` (:func:`fit_slow`, ``g`` fixed to the static gain), and a
cell between two identification stiffnesses is certified over both neighbours' models, each
with its own fit error (:meth:`InnerLoop.at`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np
import numpy.typing as npt

from fuzzkit.analysis.loop_model import InnerBox
from fuzzkit.analysis.regulation import regulation_experiment
from fuzzkit.loop.adapter import make_plant
from fuzzkit.plants.contract import task_to_base
from fuzzkit.studies.regulation import surface_height

FloatArray = npt.NDArray[np.float64]

#: Stiffnesses the inner loop is identified at (N/m): the contact load differs by 200x.
ID_STIFFNESSES = (5.0e3, 1.0e5, 1.0e6)
#: Periods of excitation per stiffness, and the seed of the binary sequence.
ID_PERIODS = 600
ID_SEED = 21
#: Periods held at the set point's indentation before the excitation starts.
WARM_UP = 100
#: A fit error (free-run NRMSE) above which the model does not describe the plant: a
#: certificate built on it is no evidence for that plant, and ``fuzzkit stability`` warns.
#: arm6 fits to 0.01 %, the planar arm to a few %; MuJoCo's dynamic arm to 95 % today.
POOR_FIT_NRMSE = 0.10
#: The static loss (``1 - s(k)`` at the stiffest identification point) from which a plant's
#: series compliance is modelled; below it the ``g`` interval carries it.
SERIES_THRESHOLD = 0.01
#: Periods each level of the static press is held, and the last periods averaged.
PRESS_HOLD = 200
PRESS_AVERAGE = 50


def series_gain(series_n_per_m: float | None, stiffness_n_per_m: float) -> float:
    """``s(k) = k_s / (k + k_s)``: the share of a commanded indentation the tool reaches, held
    still, against a contact of stiffness ``k`` (1 without a series stiffness ``k_s``)."""
    if series_n_per_m is None:
        return 1.0
    return series_n_per_m / (stiffness_n_per_m + series_n_per_m)


def poor_fit(plant: str, fit_error: float) -> str | None:
    """The warning a fit error above :data:`POOR_FIT_NRMSE` deserves, or None."""
    if fit_error <= POOR_FIT_NRMSE:
        return None
    return (
        f"the inner loop's model fits {plant} with a fit error of {100 * fit_error:.3g} % "
        f"(free-run NRMSE, above {100 * POOR_FIT_NRMSE:g} %): the certificate rests on that "
        "model, so its cells are no evidence for this plant"
    )


@dataclass(frozen=True, slots=True)
class InnerFit:
    """One identification: the fitted pole ``a``, DC gain ``g`` (of the motion over its
    static gain, :func:`press_gain`) and the free-run NRMSE."""

    stiffness_n_per_m: float
    a: float
    g: float
    nrmse: float
    q: float = 0.0
    #: the tool's held indentation over the commanded one, from :func:`press_gain`
    static_gain: float = 1.0
    #: the slow lag's pole and the fast lag's own gain (:func:`fit_slow`), None without
    b: float | None = None
    h: float | None = None


@dataclass(frozen=True, slots=True)
class InnerLoop:
    """The inner loop's model with its uncertainty: ``a`` in ``a_range``, ``g`` in ``g_range``,
    ``q`` in ``q_range``."""

    plant: str
    fits: tuple[InnerFit, ...]
    a_range: tuple[float, float]
    g_range: tuple[float, float]
    q_range: tuple[float, float] = (0.0, 0.0)
    contact_lag: tuple[float, float] = (0.0, 0.0)
    #: the servo's stiffness in series with the contact (N/m), None when it has none
    series_n_per_m: float | None = None

    @property
    def local(self) -> bool:
        """Whether the model is local in stiffness (fits with a slow lag, :func:`fit_slow`)."""
        return any(f.b is not None for f in self.fits)

    def at(self, stiffness_n_per_m: float) -> tuple[InnerBox, ...]:
        """The parameter boxes against a contact of ``stiffness_n_per_m``: the plant-wide one,
        or, for a local model, one per fit at the identification stiffnesses either side
        (:func:`bracket`), each widened by its NRMSE: ``a``, ``q`` by it, the gains ``h``,
        ``g`` by ``1 +- NRMSE``, the slow lag's time constant by ``1 +- NRMSE``; every gain
        times the series gain :func:`series_gain`."""
        s = series_gain(self.series_n_per_m, stiffness_n_per_m)
        if not self.local:
            g = (self.g_range[0] * s, self.g_range[1] * s)
            return (InnerBox(self.a_range, g, self.q_range),)
        return tuple(_box(f, s) for f in bracket(self.fits, stiffness_n_per_m))

    @property
    def fit_error(self) -> float:
        """The largest free-run NRMSE of the fits."""
        return max(f.nrmse for f in self.fits)

    def as_dict(self) -> dict[str, object]:
        """JSON form."""
        return {
            "plant": self.plant,
            "model": (
                "x[k] = q x[k-1] + (1 - q) r[k]; p[k] = a p[k-1] + (1 - a) h s(K) x[k]; "
                "y[k] = b y[k-1] + (1 - b) (g - h) s(K) x[k]; position p + y; "
                "local in stiffness: the fits either side of K"
                if self.local
                else "x[k] = q x[k-1] + (1 - q) r[k]; p[k] = a p[k-1] + (1 - a) g s(K) x[k]"
            )
            + "; s(K) = k_s / (K + k_s) at contact stiffness K (1 without a series stiffness)",
            "a": list(self.a_range),
            "q": list(self.q_range),
            "g": list(self.g_range),
            "series_stiffness_n_per_mm": None
            if self.series_n_per_m is None
            else self.series_n_per_m / 1e3,
            "contact_lag_periods": list(self.contact_lag),
            "fit_error_nrmse": self.fit_error,
            "fits": [
                {
                    "stiffness_n_per_mm": f.stiffness_n_per_m / 1e3,
                    "a": f.a,
                    "q": f.q,
                    "g": f.g,
                    "nrmse": f.nrmse,
                    "static_gain": f.static_gain,
                    "slow_pole_b": f.b,
                    "fast_gain_h": f.h,
                }
                for f in self.fits
            ],
        }


def bracket(fits: tuple[InnerFit, ...], stiffness_n_per_m: float) -> tuple[InnerFit, ...]:
    """The fits at the identification stiffnesses either side of ``stiffness_n_per_m`` (one
    when it is one of them; the nearest when it is outside their range)."""
    ordered = sorted(fits, key=lambda f: f.stiffness_n_per_m)
    below = [f for f in ordered if f.stiffness_n_per_m <= stiffness_n_per_m][-1:]
    above = [f for f in ordered if f.stiffness_n_per_m >= stiffness_n_per_m][:1]
    if below and above and below[0] is above[0]:
        return tuple(below)
    return (*below, *above)


def _widened(value: float, err: float) -> tuple[float, float]:
    """A pole's interval around ``value`` widened by ``err``, kept in ``[0, 1)``."""
    return (max(value - err, 0.0), min(value + err, 1.0 - 1e-9))


def _box(fit: InnerFit, s: float) -> InnerBox:
    """One fit's box (:meth:`InnerLoop.at`), its gains times the series gain ``s``."""
    err = fit.nrmse
    box = InnerBox(
        _widened(fit.a, err), (fit.g * (1 - err) * s, fit.g * (1 + err) * s), _widened(fit.q, err)
    )
    if fit.b is None or fit.h is None:
        return box
    tau = -1.0 / math.log(fit.b) if fit.b > 0.0 else 0.0
    b = (
        (math.exp(-1.0 / (tau / (1.0 + err))), math.exp(-1.0 / (tau * (1.0 + err))))
        if tau
        else (0.0, 0.0)
    )
    return replace(box, b=b, h=(fit.h * (1 - err) * s, fit.h * (1 + err) * s))


def excite(plant_name: str, stiffness_n_per_m: float) -> tuple[FloatArray, FloatArray]:
    """Drive ``plant_name`` in contact with a binary correction; return ``(r, p)`` per period.

    ``r``: the correction along task z the plant received, ``p``: the tool's task z (m), both
    relative to their means.
    """
    rng = np.random.default_rng(ID_SEED)
    # a level held for 1 to 8 periods: excites the whole band up to the Nyquist frequency
    holds = rng.integers(1, 9, WARM_UP + ID_PERIODS)
    signs = np.where(rng.integers(0, 2, len(holds)) > 0, 1.0, -1.0)
    level = np.repeat(signs, holds)[: WARM_UP + ID_PERIODS]
    level[:WARM_UP] = 0.0
    r, p = drive(plant_name, stiffness_n_per_m, 1.0 + 0.3 * level)
    r, p = r[WARM_UP - 1 :], p[WARM_UP - 1 :]  # one settled period before the excitation
    return r - np.mean(r), p - np.mean(p)


def drive(
    plant_name: str, stiffness_n_per_m: float, levels: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """``plant_name`` in the regulation task's contact, each period commanded to ``levels``
    times the set point's indentation: ``(r, p)``, the correction along task z it received
    and the tool's task z (m)."""
    exp = regulation_experiment(stiffness_n_per_m)
    scn = exp.scenario
    plant = make_plant(plant_name)
    plant.reset(scn, seed=0)
    depth = 10.0 / stiffness_n_per_m  # the set point's indentation
    gap = float(scn.path[0].z) - (surface_height(exp) + scn.tool.radius_m)
    r = gap + depth * levels
    p = np.empty(len(r))
    rot = scn.rotation
    for k in range(len(r)):
        sample = plant.step(task_to_base(scn, np.array([0.0, 0.0, r[k]])), 0.0)
        p[k] = float((sample.tool_position @ rot)[2])
    return r, p


def press_gain(plant_name: str, stiffness_n_per_m: float) -> float:
    """The tool's held indentation over the commanded one: commanded to 0.7 and then 1.3
    times the set point's indentation, each held :data:`PRESS_HOLD` periods, the change of
    the tool's mean position over the last :data:`PRESS_AVERAGE` periods of each level."""
    levels = np.repeat([0.7, 1.3], PRESS_HOLD)
    r, p = drive(plant_name, stiffness_n_per_m, levels)
    low, high = slice(PRESS_HOLD - PRESS_AVERAGE, PRESS_HOLD), slice(-PRESS_AVERAGE, None)
    return float((np.mean(p[high]) - np.mean(p[low])) / (np.mean(r[high]) - np.mean(r[low])))


def series_stiffness(gains: dict[float, float]) -> float | None:
    """The series stiffness ``k_s`` (N/m) that best explains the static gains ``{k: s}``
    (least squares on ``1/s - 1 = k / k_s``), or None when the stiffest loses less than
    :data:`SERIES_THRESHOLD` of the command."""
    stiffest = max(gains)
    if 1.0 - gains[stiffest] < SERIES_THRESHOLD:
        return None
    k = np.array(list(gains))
    y = 1.0 / np.array(list(gains.values())) - 1.0
    return float(np.dot(k, k) / np.dot(k, y))


def simulate(r: FloatArray, a: float, q: float, g: float) -> FloatArray:
    """The cascade's free-run response to ``r`` from rest at ``r[0]``."""
    x = np.empty_like(r)
    p = np.empty_like(r)
    x[0] = r[0]
    p[0] = g * r[0]
    for k in range(1, len(r)):
        x[k] = q * x[k - 1] + (1.0 - q) * r[k]
        p[k] = a * p[k - 1] + (1.0 - a) * g * x[k]
    return p


def fit(r: FloatArray, p: FloatArray, stiffness_n_per_m: float) -> InnerFit:
    """The cascade minimising the free-run error against ``p`` (with an output offset)."""
    from scipy.optimize import least_squares

    def residual(theta: FloatArray) -> FloatArray:
        a, q, g, c = theta
        out: FloatArray = simulate(r, a, q, g) + c - p
        return out

    # start from the one-lag least-squares fit, q small
    m = np.column_stack([p[:-1], r[1:], np.ones(len(r) - 1)])
    (a0, b0, _), *_ = np.linalg.lstsq(m, p[1:], rcond=None)
    a0 = min(max(float(a0), 0.0), 0.99)
    g0 = min(max(float(b0) / (1.0 - a0), 0.5), 2.0)
    sols = [
        least_squares(
            residual,
            np.array([a0, q0, g0, 0.0]),
            bounds=([0.0, 0.0, 0.5, -1.0], [0.999, 0.999, 2.0, 1.0]),
            xtol=1e-14,
            ftol=1e-14,
            gtol=1e-14,
        )
        for q0 in (0.0, 0.2, 0.5)
    ]
    sol = min(sols, key=lambda s: float(s.cost))
    a, q, g, _ = (float(v) for v in sol.x)
    nrmse = float(np.sqrt(np.mean(sol.fun**2)) / np.std(p))
    return InnerFit(stiffness_n_per_m, a, g, nrmse, q)


def simulate_slow(r: FloatArray, a: float, q: float, h: float, b: float) -> FloatArray:
    """The position ``p + y`` of the cascade with a slow lag and unit gain (the fast lag's
    gain ``h``, the slow lag's ``1 - h``) from rest at ``r[0]``."""
    from scipy.signal import lfilter

    d = r - r[0]
    x = lfilter([1.0 - q], [1.0, -q], d)
    p = lfilter([(1.0 - a) * h], [1.0, -a], x)
    y = lfilter([(1.0 - b) * (1.0 - h)], [1.0, -b], x)
    out: FloatArray = r[0] + p + y
    return out


def fit_slow(r: FloatArray, p: FloatArray, stiffness_n_per_m: float) -> InnerFit:
    """The cascade with a slow lag (:func:`simulate_slow`, unit gain: ``p`` is the motion over
    its series gain) minimising the free-run error against ``p`` (with an output offset)."""
    from scipy.optimize import least_squares

    def residual(theta: FloatArray) -> FloatArray:
        a, q, h, b, c = theta
        out: FloatArray = simulate_slow(r, a, q, h, b) + c - p
        return out

    sols = [
        least_squares(
            residual,
            np.array([0.5, 0.5, h0, 0.9, 0.0]),
            bounds=([0.0, 0.0, 0.0, 0.0, -1.0], [0.999, 0.999, 5.0, 0.999, 1.0]),
        )
        for h0 in (1.0, 3.0)
    ]
    sol = min(sols, key=lambda s: float(s.cost))
    a, q, h, b, _ = (float(v) for v in sol.x)
    nrmse = float(np.sqrt(np.mean(sol.fun**2)) / np.std(p))
    return InnerFit(stiffness_n_per_m, a, 1.0, nrmse, q, b=b, h=h)


#: Where a plant with a series compliance is identified: its contact changes the inner loop's
#: dynamics, so its model is local in stiffness (:meth:`InnerLoop.at`), fitted at each of
#: these, the calibration grid's stiffnesses (docs/stability.md): the validation grid's lie
#: between them and are never identified at.
LOCAL_ID_STIFFNESSES = (5e3, 1e4, 2e4, 5e4, 1e5, 2e5, 5e5, 1e6)


@lru_cache(maxsize=4)
def identify(plant_name: str) -> InnerLoop:
    """Identify the inner loop of ``plant_name`` at :data:`ID_STIFFNESSES` (cached): the
    static press at each, the series stiffness from them, then the fits of the motion over
    its series gain; a plant with a series stiffness is pressed and fitted, with the slow lag
    (:func:`fit_slow`), at every one of :data:`LOCAL_ID_STIFFNESSES` instead."""
    statics = {k: press_gain(plant_name, k) for k in ID_STIFFNESSES}
    ks = series_stiffness(statics)
    stiffnesses: tuple[float, ...] = ID_STIFFNESSES
    fitter = fit
    if ks is not None:
        stiffnesses, fitter = LOCAL_ID_STIFFNESSES, fit_slow
        statics.update({k: press_gain(plant_name, k) for k in stiffnesses if k not in statics})
        ks = series_stiffness(statics)
    fits = []
    for k in stiffnesses:
        r, p = excite(plant_name, k)
        fits.append(replace(fitter(r, p / series_gain(ks, k), k), static_gain=statics[k]))
    err = max(f.nrmse for f in fits)
    a_lo = max(min(f.a for f in fits) - err, 0.0)
    a_hi = min(max(f.a for f in fits) + err, 1.0 - 1e-9)
    q_lo = max(min(f.q for f in fits) - err, 0.0)
    q_hi = min(max(f.q for f in fits) + err, 1.0 - 1e-9)
    g_lo = min(f.g for f in fits) * (1.0 - err)
    g_hi = max(f.g for f in fits) * (1.0 + err)
    return InnerLoop(
        plant_name,
        tuple(fits),
        (a_lo, a_hi),
        (g_lo, g_hi),
        (q_lo, q_hi),
        contact_lag(plant_name),
        ks,
    )


#: Uncertainty (periods) carried on a substep plant's derived contact/sensor lag: pymunk's
#: bodies and constraints add lag the per-period model does not have (docs/stability.md).
SUBSTEP_LAG_UNCERTAINTY = 0.25


def contact_lag(plant_name: str) -> tuple[float, float]:
    """The interval of the contact/sensor lag, in periods (:func:`~fuzzkit.analysis.loop_model.
    substep_lag`): arm6 evaluates contact and sensor once, at the period's end (0); the planar
    arm's sensor filters its physics substeps (derived value +- the carried uncertainty)."""
    from fuzzkit.analysis.loop_model import substep_lag

    plant = make_plant(plant_name)
    params = getattr(plant, "params", None)
    substeps = getattr(params, "substeps", None) if plant_name == "planar" else None
    if not (isinstance(substeps, int) and substeps > 1):
        return (0.0, 0.0)
    scn = regulation_experiment().scenario
    lag = substep_lag(substeps, scn.sensor.cutoff_hz, scn.period_s)
    return (max(lag - SUBSTEP_LAG_UNCERTAINTY, 0.0), min(lag + SUBSTEP_LAG_UNCERTAINTY, 1.0))
