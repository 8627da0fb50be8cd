"""Which tool pose goes with a wrench sample, for a spec that compensates the tool's weight.

By default a wrench takes the latest pose received (none yet: no rotation, and the controller
holds as for a missing sample): the pose and the wrench come from two drivers, and the node does
not wait. With ``--pose-sync`` a wrench waits until a pose stamped at or after its own stamp has
arrived, then takes the latest pose stamped at or before it: the pairing is then decided by the
stamps alone, whatever order the two topics arrive in (a plant stepping in lockstep publishes
both each period). At most ``depth`` wrenches wait; when more come, the oldest goes on with the
pose there is, so a pose topic that falls silent does not hold samples without end.
"""

from __future__ import annotations

from collections import deque
from typing import Generic, TypeVar

Item = TypeVar("Item")
Rotation = list[float] | None


class PosePairing(Generic[Item]):
    """Wrenches (any ``Item``, with their stamps) paired with poses (module docstring)."""

    def __init__(self, wait: bool, depth: int) -> None:
        self.wait = wait
        self.depth = depth
        self._poses: deque[tuple[int, list[float]]] = deque(maxlen=max(depth, 1) + 1)
        self._pending: deque[tuple[int, Item]] = deque()

    def clear(self) -> None:
        """Forget the waiting wrenches (the poses stay: the tool has not moved)."""
        self._pending.clear()

    def pose(self, stamp_ns: int, rotation: list[float]) -> list[tuple[Item, Rotation]]:
        """A pose arrived: the wrenches it releases, in arrival order, each with its rotation."""
        self._poses.append((stamp_ns, rotation))
        return self._release()

    def wrench(self, stamp_ns: int, item: Item) -> list[tuple[Item, Rotation]]:
        """A wrench arrived: the wrenches ready now (it, or none while it waits)."""
        if not self.wait:
            return [(item, self._poses[-1][1] if self._poses else None)]
        self._pending.append((stamp_ns, item))
        return self._release()

    def _release(self) -> list[tuple[Item, Rotation]]:
        out: list[tuple[Item, Rotation]] = []
        newest = max((s for s, _ in self._poses), default=None)
        while self._pending:
            stamp, item = self._pending[0]
            ready = newest is not None and newest >= stamp
            if not ready and len(self._pending) <= self.depth:
                break
            self._pending.popleft()
            out.append((item, self._at(stamp)))
        return out

    def _at(self, stamp_ns: int) -> Rotation:
        """The latest pose stamped at or before ``stamp_ns`` (else the earliest there is)."""
        best: tuple[int, list[float]] | None = None
        for s, r in self._poses:
            if s <= stamp_ns and (best is None or s >= best[0]):
                best = (s, r)
        if best is None:
            return self._poses[0][1] if self._poses else None
        return best[1]
