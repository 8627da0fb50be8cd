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
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import numpy.typing as npt

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
    """One identification: the fitted pole ``a``, DC gain ``g`` and the free-run NRMSE."""

    stiffness_n_per_m: float
    a: float
    g: float
    nrmse: float
    q: float = 0.0


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

    @property
    def fit_error(self) -> float:
        """The largest free-run NRMSE of the fits."""
        return max(f.nrmse for f in self.fits)

    def as_dict(self) -> dict[str, object]:
        """JSON form."""
        return {
            "plant": self.plant,
            "model": "x[k] = q x[k-1] + (1 - q) r[k]; p[k] = a p[k-1] + (1 - a) g x[k]",
            "a": list(self.a_range),
            "q": list(self.q_range),
            "g": list(self.g_range),
            "contact_lag_periods": list(self.contact_lag),
            "fit_error_nrmse": self.fit_error,
            "fits": [
                {
                    "stiffness_n_per_mm": f.stiffness_n_per_m / 1e3,
                    "a": f.a,
                    "q": f.q,
                    "g": f.g,
                    "nrmse": f.nrmse,
                }
                for f in self.fits
            ],
        }


def excite(plant_name: str, stiffness_n_per_m: float) -> tuple[FloatArray, FloatArray]:
    """Drive ``plant_name`` in contact with a binary correction; return ``(r, p)`` per period.

    ``r``: the correction along task z the plant received, ``p``: the tool's task z (m), both
    relative to their means.
    """
    exp = regulation_experiment(stiffness_n_per_m)
    scn = exp.scenario
    plant = make_plant(plant_name)
    plant.reset(scn, seed=0)
    depth = 10.0 / stiffness_n_per_m  # the set point's indentation
    gap = float(scn.path[0].z) - (surface_height(exp) + scn.tool.radius_m)
    rng = np.random.default_rng(ID_SEED)
    # a level held for 1 to 8 periods: excites the whole band up to the Nyquist frequency
    holds = rng.integers(1, 9, WARM_UP + ID_PERIODS)
    signs = np.where(rng.integers(0, 2, len(holds)) > 0, 1.0, -1.0)
    level = np.repeat(signs, holds)[: WARM_UP + ID_PERIODS]
    level[:WARM_UP] = 0.0
    r = gap + depth * (1.0 + 0.3 * level)
    p = np.empty(len(r))
    rot = scn.rotation
    for k in range(len(r)):
        sample = plant.step(task_to_base(scn, np.array([0.0, 0.0, r[k]])), 0.0)
        p[k] = float((sample.tool_position @ rot)[2])
    r, p = r[WARM_UP - 1 :], p[WARM_UP - 1 :]  # one settled period before the excitation
    return r - np.mean(r), p - np.mean(p)


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


@lru_cache(maxsize=4)
def identify(plant_name: str) -> InnerLoop:
    """Identify the inner loop of ``plant_name`` at :data:`ID_STIFFNESSES` (cached)."""
    fits = tuple(fit(*excite(plant_name, k), k) for k in ID_STIFFNESSES)
    err = max(f.nrmse for f in fits)
    a_lo = max(min(f.a for f in fits) - err, 0.0)
    a_hi = min(max(f.a for f in fits) + err, 1.0 - 1e-9)
    q_lo = max(min(f.q for f in fits) - err, 0.0)
    q_hi = min(max(f.q for f in fits) + err, 1.0 - 1e-9)
    g_lo = min(f.g for f in fits) * (1.0 - err)
    g_hi = max(f.g for f in fits) * (1.0 + err)
    return InnerLoop(
        plant_name, fits, (a_lo, a_hi), (g_lo, g_hi), (q_lo, q_hi), contact_lag(plant_name)
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
