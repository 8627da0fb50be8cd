"""The searched gains of each controller and their bounds (searched as ``log10`` values)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from fuzzkit.control.names import GAIN_KEYS
from fuzzkit.errors import ConfigError

Vec = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class GainSpace:
    """The searched gains and their bounds (gain units, both > 0; searched as log10)."""

    names: tuple[str, ...]
    lower: tuple[float, ...]
    upper: tuple[float, ...]

    def __post_init__(self) -> None:
        if not (len(self.names) == len(self.lower) == len(self.upper)) or not self.names:
            raise ConfigError("GainSpace: names, lower and upper must have the same length > 0")
        for n, lo, hi in zip(self.names, self.lower, self.upper, strict=True):
            if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 < lo < hi):
                raise ConfigError(f"GainSpace: bounds of {n} must satisfy 0 < lower < upper")

    @property
    def log_bounds(self) -> tuple[Vec, Vec]:
        """Lower and upper bounds of the searched log10 values."""
        return np.log10(np.asarray(self.lower)), np.log10(np.asarray(self.upper))

    def to_gains(self, x: Sequence[float] | Vec) -> dict[str, float]:
        """The gains at the log10 point ``x``."""
        return {n: float(10.0 ** float(v)) for n, v in zip(self.names, x, strict=True)}

    def to_x(self, gains: Mapping[str, float]) -> Vec:
        """The log10 point of ``gains`` (clipped into the bounds)."""
        lo, hi = self.log_bounds
        x = np.array([math.log10(gains[n]) for n in self.names])
        return np.asarray(np.clip(x, lo, hi), dtype=np.float64)


#: Search spaces per controller. PI gains in m/N: loop gain ``Ki*k`` per period must stay
#: below about 1, so ``ki`` reaches down to 1e-8 m/N for stiff (1000 N/mm) environments. Fuzzy
#: ``ki``, ``kp``: 1/N (full scale of e from 1 N to 1000 N); ``kx``: metres per step.
SPACES: dict[str, GainSpace] = {
    "pi": GainSpace(GAIN_KEYS["pi"], (1.0e-7, 1.0e-8), (1.0e-3, 1.0e-3)),
    "fuzzy-pi": GainSpace(GAIN_KEYS["fuzzy-pi"], (1.0e-3, 1.0e-3, 1.0e-6), (10.0, 1.0, 1.0e-2)),
}
