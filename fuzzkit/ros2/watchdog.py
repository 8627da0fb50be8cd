"""The node's watchdog: no sample stepped for N periods stops the output, as a robot's force
interface stops when its sensor falls silent.

It is armed by the first sample stepped and fed by every one after it (a late sample, dropped,
does not feed it). It expires when the node's clock (``use_sim_time``: ``/clock``) has gone
``periods`` periods past the last sample, or when a sample's stamp comes more than ``periods``
periods after the previous one (the sensor's own record of the silence). Once expired it stays
so until :meth:`Watchdog.reset` (the node's ``reset`` service): a force loop that lost its
sensor does not resume on its own.
"""

from __future__ import annotations


class Watchdog:
    """Expiry after ``periods`` periods of ``period_ns`` without a sample (module docstring)."""

    def __init__(self, period_ns: int, periods: int) -> None:
        if periods < 1:
            raise ValueError(f"the watchdog needs at least 1 period, got {periods}")
        self.periods = periods
        self.timeout_ns = periods * period_ns
        self.reset()

    def reset(self) -> None:
        """Disarmed and not expired: the next sample arms it."""
        self.last_ns: int | None = None
        self.expired = False

    def feed(self, now_ns: int) -> None:
        """A sample was stepped at ``now_ns`` (the node's clock)."""
        self.last_ns = now_ns

    def expire(self) -> None:
        """Expire now (a gap in the stamps longer than the timeout)."""
        self.expired = True

    def check(self, now_ns: int) -> bool:
        """True when the watchdog expires at this check (False before, and once expired)."""
        if self.expired or self.last_ns is None:
            return False
        if now_ns - self.last_ns > self.timeout_ns:
            self.expired = True
            return True
        return False
