"""Which control period a stamped wrench sample fills, as the samples arrive.

The node runs one controller step per period of the spec, on a grid anchored at the first
sample's stamp (``header.stamp``): period ``k`` is the grid time ``start + k*T``, and a sample
fills the period whose grid time is nearest its stamp (``k = round((stamp - start) / T)``, so
a sensor whose stamps jitter by less than half a period fills every period once). A sample is
stepped as soon as it arrives; the periods between the last one stepped and its own, which no
sample filled, are stepped first as missing samples (NaN: the controller holds its correction
and says HELD), as a dropout is everywhere else in the kit. A sample whose period was already
stepped (a second sample in one period, or a stamp older than the last one stepped: out of
order) is late: it is dropped and counted, since a controller step cannot be taken back.

This is the live counterpart of ``fuzzkit replay`` on a log: a log with one row per period
(NaN rows for the periods without a sample) replays to exactly the node's corrections. A bag
replayed by ``fuzzkit replay --forces BAG`` is resampled after the fact (the last sample stamped
in each period, in stamp order), so the two agree on any bag whose stamps lie on the grid and
arrive in order; where a sample arrives late the node has already stepped its period as
missing, and the bag's replay, which can wait, has not.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class Placement:
    """Where one sample falls: its ``period`` (from the first sample, 0-based), the ``missing``
    periods before it that are stepped as missing samples first, and whether it is ``late``
    (its period was already stepped: dropped)."""

    period: int
    missing: int
    late: bool


class SampleClock:
    """The grid of one run (see the module docstring); :meth:`restart` forgets its anchor."""

    def __init__(self, period_s: float) -> None:
        self.period_ns = round(period_s * 1e9)
        if self.period_ns <= 0:
            raise ValueError(f"the period must be at least 1 ns, got {period_s!r} s")
        self.restart()

    def restart(self) -> None:
        """No grid until the next sample, which is period 0."""
        self.start_ns: int | None = None
        #: the next period not yet stepped
        self.next_period = 0

    def place(self, stamp_ns: int) -> Placement:
        """The placement of a sample stamped ``stamp_ns``; not late: the periods up to it count
        as stepped from now on."""
        if self.start_ns is None:
            self.start_ns = stamp_ns
        half = self.period_ns // 2
        period = (stamp_ns - self.start_ns + half) // self.period_ns
        if period < self.next_period:
            return Placement(period, 0, True)
        missing = period - self.next_period
        self.next_period = period + 1
        return Placement(period, missing, False)

    def stamp_ns(self, period: int) -> int:
        """The grid time of ``period`` (ns), the stamp of its correction."""
        if self.start_ns is None:
            raise ValueError("no sample yet: the grid has no anchor")
        return self.start_ns + period * self.period_ns
