"""The wrist-sensor front end: tare, gravity compensation and a first-order low-pass.

What a real F/T sensor needs before ``e = f_d - f`` (``docs/controller.md``, "The front end,
sample by sample", is the contract every implementation matches):

* gravity compensation: the raw reading ``f_raw = f + w(R) + b`` carries the tool's weight
  ``w(R) = m*g*(r31, r32, r33)`` (``R`` world-from-sensor, world z up; force = what the tool
  exerts on the environment) and the sensor's bias ``b``; ``c = f_raw - w(R) - bias``;
* tare: ``bias`` is the mean of ``f_raw - w(R)`` over the first N valid samples after a reset
  or a tare request (0 samples: no tare, bias 0);
* low-pass: ``y += alpha * (c - y)`` with ``alpha = 1 - exp(-2*pi*fc*T)``
  (:meth:`fuzzkit.control.spec.SensorSpec.lowpass_alpha`); the first sample after a reset or a
  tare initialises ``y = c``.

:class:`~fuzzkit.control.controllers.HybridForceController` calls these in that order around
its spike gate and trip rule; this module holds the arithmetic and the state.

Twins: this is the **reference** copy of the front end; the compiled loop's copy
(:mod:`fuzzkit.loop.compiled.period`, ``tests/test_spec_runs.py``) and the generated
controller's (``tests/test_controller_codegen.py``) are tested against it, so it stays a
separate implementation on purpose.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from fuzzkit.control.spec import STANDARD_GRAVITY_M_S2
from fuzzkit.errors import ConfigError

Vec = npt.NDArray[np.float64]


class FrontEnd:
    """Tare, gravity compensation and low-pass of one wrist sensor's force samples.

    Parameters
    ----------
    tare_samples : N, the free-air samples averaged into the bias (0: no tare).
    mass_kg : the tool's mass below the sensor (None: no gravity compensation, and no rotation
        is needed).
    alpha : the low-pass gain per sample, in (0, 1] (1: no filter).
    """

    def __init__(
        self, tare_samples: int = 0, mass_kg: float | None = None, alpha: float = 1.0
    ) -> None:
        if tare_samples < 0:
            raise ConfigError(f"tare_samples must be >= 0 (got {tare_samples})")
        if mass_kg is not None and not (math.isfinite(mass_kg) and mass_kg >= 0.0):
            raise ConfigError(f"mass_kg must be a finite number >= 0 (got {mass_kg})")
        if not 0.0 < alpha <= 1.0:
            raise ConfigError(f"the low-pass gain alpha must be in (0, 1] (got {alpha})")
        self.tare_samples = tare_samples
        self.mass_kg = mass_kg
        self.alpha = alpha
        self.reset()

    @property
    def needs_rotation(self) -> bool:
        """True when gravity compensation is on: every sample needs the tool's rotation."""
        return self.mass_kg is not None

    def reset(self) -> None:
        """Forget the bias and the filter; the next N valid samples are the tare."""
        self.bias = np.zeros(3)
        self._sum = np.zeros(3)
        self._count = 0
        self.taring = self.tare_samples > 0
        self._y: Vec | None = None

    def request_tare(self) -> None:
        """Take the next N valid samples as a new tare (the tool must be in free air)."""
        if self.tare_samples > 0:
            self._sum = np.zeros(3)
            self._count = 0
            self.taring = True

    def weight(self, rotation: Vec | None) -> Vec:
        """``w(R) = m*g*(r31, r32, r33)``: the tool's weight as the sensor reads it (N)."""
        if self.mass_kg is None or rotation is None:
            return np.zeros(3)
        return np.asarray(self.mass_kg * STANDARD_GRAVITY_M_S2 * rotation[2], dtype=np.float64)

    def tare(self, raw: Vec, rotation: Vec | None) -> bool:
        """Add one sample to the running tare; True when it completed the tare.

        A sample counts only when all three axes are finite (the caller holds the others).
        """
        if not bool(np.all(np.isfinite(raw))):
            return False
        self._sum = self._sum + (raw - self.weight(rotation))
        self._count += 1
        if self._count < self.tare_samples:
            return False
        self.bias = self._sum / self._count
        self.taring = False
        self._y = None
        return True

    def compensate(self, raw: Vec, rotation: Vec | None) -> Vec:
        """``c = f_raw - w(R) - bias``; a non-finite axis gives 0 (a motion-only axis: the caller
        has refused samples with a non-finite force-controlled axis)."""
        c = raw - self.weight(rotation) - self.bias
        return np.where(np.isfinite(c), c, 0.0)

    def filter(self, c: Vec) -> Vec:
        """One low-pass step on a compensated sample the spike gate accepted."""
        if self._y is None or self.alpha == 1.0:
            self._y = c.copy()
        else:
            self._y = self._y + self.alpha * (c - self._y)
        return self._y.copy()
