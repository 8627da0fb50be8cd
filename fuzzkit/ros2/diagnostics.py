"""The node's status as ``diagnostic_msgs/DiagnosticArray``: the controller's status bits by
name (:data:`fuzzkit.control.status.BITS`), the watchdog, and the node's counters.

One ``DiagnosticStatus`` named ``fuzzkit/NAME`` (the spec's name), its ``hardware_id`` the
node's fully qualified name (two nodes of one spec tell apart). Its level: ERROR when the
safety limit tripped or the watchdog stopped the output, WARN when the last sample was held or
rejected or a correction limit acted, OK otherwise; its message the set bits' names
(``ENGAGED|SATURATED``, ``0`` when none). The values: every bit as ``true``/``false``, the bit
mask (``status``), the last period stepped (``period``, -1 before the first), ``watchdog``
(``expired``/``ok``), and the counters of :class:`fuzzkit.ros2.stepper.Counters`.
"""

from __future__ import annotations

from dataclasses import asdict
from typing import Any

from fuzzkit.control import status as st
from fuzzkit.ros2.messages import time_msg
from fuzzkit.ros2.stepper import Counters

#: The bits that make the status a warning (the others are the normal course of a run).
WARN_BITS = st.HELD | st.REJECTED | st.SATURATED


def level_of(status: int, watchdog_expired: bool) -> int:
    """``DiagnosticStatus`` level: 2 (ERROR), 1 (WARN) or 0 (OK), module docstring."""
    if watchdog_expired or status & st.TRIPPED:
        return 2
    if status & WARN_BITS:
        return 1
    return 0


def status_values(
    status: int, period: int, watchdog_expired: bool, counters: Counters
) -> list[tuple[str, str]]:
    """The key-value pairs of the node's status, in a fixed order."""
    pairs = [(name, "true" if status & bit else "false") for name, bit in st.BITS.items()]
    pairs += [
        ("status", str(status)),
        ("period", str(period)),
        ("watchdog", "expired" if watchdog_expired else "ok"),
    ]
    pairs += [(k, str(v)) for k, v in asdict(counters).items()]
    return pairs


def diagnostic_array(
    name: str,
    node: str,
    stamp: int,
    status: int,
    period: int,
    watchdog_expired: bool,
    counters: Counters,
) -> Any:
    """The ``DiagnosticArray`` the node publishes (module docstring)."""
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

    entry = DiagnosticStatus()
    entry.level = bytes([level_of(status, watchdog_expired)])
    entry.name = f"fuzzkit/{name}"
    entry.hardware_id = node
    words = st.describe(status)
    entry.message = f"watchdog expired: no sample; {words}" if watchdog_expired else words
    entry.values = [
        KeyValue(key=k, value=v)
        for k, v in status_values(status, period, watchdog_expired, counters)
    ]
    array = DiagnosticArray()
    array.header.stamp = time_msg(stamp)
    array.status = [entry]
    return array
