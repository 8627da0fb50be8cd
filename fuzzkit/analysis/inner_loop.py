"""The inner motion loop's response from correction to tool position, identified on a plant.

Each plant (``planar``, ``arm6``) is driven in contact with the flat surface of the regulation
task (:mod:`fuzzkit.analysis.regulation`) by a pseudo-random binary correction along task z
around the indentation of the set point, one controller period at a time, and the tool's z is
recorded. A first-order discrete model per period,

    p[k] = a * p[k-1] + (1 - a) * g * r[k] + c        (r[k]: the correction the plant receives)

is fitted by least squares at several stiffnesses. The fit error is the free-run simulation
error of the fitted model relative to the measured motion (NRMSE). The model the certificate
uses carries it as uncertainty: ``a`` over the range of the fits widened by the largest NRMSE,
``g`` over the range of the fits times ``1 +- NRMSE``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import numpy.typing as npt

from fuzzkit.analysis.regulation import SURFACE_Z, regulation_experiment
from fuzzkit.plants.contract import task_to_base
from fuzzkit.studies.plants import make_plant

FloatArray = npt.NDArray[np.float64]

#: Stiffnesses the inner loop is identified at (N/m): the contact load differs by 200x.
ID_STIFFNESSES = (5.0e3, 1.0e5, 1.0e6)
#: Periods of excitation per stiffness, and the seed of the binary sequence.
ID_PERIODS = 600
ID_SEED = 21
#: Periods held at the set point's indentation before the excitation starts.
WARM_UP = 100


@dataclass(frozen=True, slots=True)
class InnerFit:
    """One identification: the fitted pole ``a``, DC gain ``g`` and the free-run NRMSE."""

    stiffness_n_per_m: float
    a: float
    g: float
    nrmse: float


@dataclass(frozen=True, slots=True)
class InnerLoop:
    """The inner loop's model with its uncertainty: ``a`` in ``a_range``, ``g`` in ``g_range``."""

    plant: str
    fits: tuple[InnerFit, ...]
    a_range: tuple[float, float]
    g_range: tuple[float, float]

    @property
    def fit_error(self) -> float:
        """The largest free-run NRMSE of the fits."""
        return max(f.nrmse for f in self.fits)

    def as_dict(self) -> dict[str, object]:
        """JSON form."""
        return {
            "plant": self.plant,
            "model": "p[k] = a p[k-1] + (1 - a) g r[k]",
            "a": list(self.a_range),
            "g": list(self.g_range),
            "fit_error_nrmse": self.fit_error,
            "fits": [
                {
                    "stiffness_n_per_mm": f.stiffness_n_per_m / 1e3,
                    "a": f.a,
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
    gap = float(scn.path[0].z) - (SURFACE_Z + scn.tool.radius_m)
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


def fit(r: FloatArray, p: FloatArray, stiffness_n_per_m: float) -> InnerFit:
    """Least-squares ``p[k] = a p[k-1] + b r[k] + c``; ``g = b / (1 - a)``; free-run NRMSE."""
    m = np.column_stack([p[:-1], r[1:], np.ones(len(r) - 1)])
    (a, b, c), *_ = np.linalg.lstsq(m, p[1:], rcond=None)
    sim = np.empty_like(p)
    sim[0] = p[0]
    for k in range(1, len(p)):
        sim[k] = a * sim[k - 1] + b * r[k] + c
    nrmse = float(np.sqrt(np.mean((sim - p) ** 2)) / np.std(p))
    return InnerFit(stiffness_n_per_m, float(a), float(b / (1.0 - a)), nrmse)


@lru_cache(maxsize=4)
def identify(plant_name: str) -> InnerLoop:
    """Identify the inner loop of ``plant_name`` at :data:`ID_STIFFNESSES` (cached)."""
    fits = tuple(fit(*excite(plant_name, k), k) for k in ID_STIFFNESSES)
    err = max(f.nrmse for f in fits)
    a_lo = max(min(f.a for f in fits) - err, 0.0)
    a_hi = min(max(f.a for f in fits) + err, 1.0 - 1e-9)
    g_lo = min(f.g for f in fits) * (1.0 - err)
    g_hi = max(f.g for f in fits) * (1.0 + err)
    return InnerLoop(plant_name, fits, (a_lo, a_hi), (g_lo, g_hi))
