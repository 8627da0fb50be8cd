"""Sensor faults injected into the measured force between the plant and the controller.

:data:`FAULTS` names the fault kinds at the strength the test suite, ``make verify`` and
``fuzzkit simulate --fault`` use; everything else refers to them by name.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import numpy.typing as npt

from fuzzkit.errors import ConfigError

Vec = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class Faults:
    """Sensor faults injected into the measured force before the controller sees it.

    ``nan_probability``: each sample is NaN with this probability. ``dropout``: ``(start_s,
    length_s)`` during which every sample is missing (NaN). ``spike_probability`` /
    ``spike_n``: a sample gets a random-signed spike of this size on x and z (the plane of the
    experiments). ``delay_steps``: extra sensor-to-controller delay (periods), added to the
    run's sensor latency. ``offset``: ``(start_s, length_s, force_n)``, a force added on z
    during that window (a sensor step, or a real push past the safety limit: the over-limit
    fault). Seeded by ``seed``, deterministic.
    """

    nan_probability: float = 0.0
    dropout: tuple[float, float] | None = None
    spike_probability: float = 0.0
    spike_n: float = 0.0
    delay_steps: int = 0
    seed: int = 0
    offset: tuple[float, float, float] | None = None

    def __post_init__(self) -> None:
        problems = []
        for name in ("nan_probability", "spike_probability"):
            p = getattr(self, name)
            if not 0.0 <= p <= 1.0:
                problems.append(f"{name} must be in [0, 1] (got {p})")
        if not self.spike_n >= 0.0:
            problems.append(f"spike_n must be >= 0 (got {self.spike_n})")
        if self.dropout is not None and not (self.dropout[0] >= 0.0 and self.dropout[1] >= 0.0):
            problems.append(f"dropout start and length must be >= 0 (got {self.dropout})")
        if self.offset is not None and not (
            self.offset[0] >= 0.0 and self.offset[1] >= 0.0 and np.isfinite(self.offset[2])
        ):
            problems.append(f"offset start and length must be >= 0, force finite ({self.offset})")
        if self.delay_steps < 0:
            problems.append(f"delay_steps must be >= 0 (got {self.delay_steps})")
        if problems:
            raise ConfigError("faults: " + "; ".join(problems))


#: The fault kinds by name, at the strength the safety tests use (seed 0; see :func:`fault`).
FAULTS: dict[str, Faults] = {
    "none": Faults(),
    "spike": Faults(spike_probability=0.03, spike_n=40.0),
    "nan": Faults(nan_probability=0.2),
    "dropout": Faults(dropout=(2.2, 0.1)),
    "delay": Faults(delay_steps=2),
}


def fault(name: str, seed: int = 0) -> Faults:
    """The fault kind called ``name`` (see :data:`FAULTS`), its randomness seeded by ``seed``."""
    faults = FAULTS.get(name)
    if faults is None:
        raise ConfigError(f"unknown fault {name!r} (expected one of {', '.join(FAULTS)})")
    return replace(faults, seed=seed)


def fault_name(faults: Faults) -> str:
    """The name of ``faults`` in :data:`FAULTS` (any seed), or ``custom``."""
    unseeded = replace(faults, seed=0)
    return next((name for name, f in FAULTS.items() if f == unseeded), "custom")


class FaultInjector:
    """Applies :class:`Faults` to one run's measured force samples, in order."""

    def __init__(self, faults: Faults) -> None:
        self.faults = faults
        self.rng = np.random.default_rng(faults.seed)

    def __call__(self, t_s: float, force: Vec) -> Vec:
        """The sample the sensor interface delivers at ``t_s`` for the true reading ``force``."""
        f = self.faults
        out = force.copy()
        if f.spike_probability > 0.0 and self.rng.random() < f.spike_probability:
            out = out + self.rng.choice([-1.0, 1.0]) * f.spike_n * np.array([1.0, 0.0, 1.0])
        if f.offset is not None and f.offset[0] <= t_s < f.offset[0] + f.offset[1]:
            out = out + np.array([0.0, 0.0, f.offset[2]])
        if f.nan_probability > 0.0 and self.rng.random() < f.nan_probability:
            out = np.full(3, np.nan)
        if f.dropout is not None and f.dropout[0] <= t_s < f.dropout[0] + f.dropout[1]:
            out = np.full(3, np.nan)
        return out


def fault_schedule(faults: Faults, periods: int) -> tuple[Vec, npt.NDArray[np.bool_]]:
    """The random part of ``periods`` samples of :class:`FaultInjector`, drawn up front in its
    order: per period the spike sign (0: none) and whether the sample is NaN. The compiled loop
    (:mod:`fuzzkit.loop.compiled`) injects from it; the injector's draws are the same."""
    rng = np.random.default_rng(faults.seed)
    spike = np.zeros(periods)
    nan = np.zeros(periods, dtype=bool)
    for k in range(periods):
        if faults.spike_probability > 0.0 and rng.random() < faults.spike_probability:
            spike[k] = rng.choice([-1.0, 1.0])
        if faults.nan_probability > 0.0 and rng.random() < faults.nan_probability:
            nan[k] = True
    return spike, nan
