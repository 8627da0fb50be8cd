"""The status bit field a controller step returns: the one definition every implementation
(the reference controller, generated C and Python) mirrors.

Bits are independent; a step sets every one that applies to it. ``NAME_controller_step`` in C
and ``Controller.step`` in Python return the same integer for the same sample.
"""

from __future__ import annotations

#: The force loop has taken over (the engagement debounce passed); stays set until reset.
ENGAGED = 1 << 0
#: This sample was not usable: missing (NaN/inf on a force-controlled axis; no or a non-finite
#: tool rotation while gravity compensation is on), rejected by the spike gate, or consumed by
#: the tare. The correction is held.
HELD = 1 << 1
#: The force safety limit tripped; latched until reset. The correction is frozen.
TRIPPED = 1 << 2
#: Tripped and still backing off (the back-off distance is not yet covered).
RETREATING = 1 << 3
#: A correction limit acted in this step on some axis: ``|u|`` clamped to ``correction_m`` or
#: ``|du|`` clamped to ``step_m``.
SATURATED = 1 << 4
#: The tare is collecting free-air samples (the first N valid ones, or N after a request).
TARING = 1 << 5
#: The spike gate rejected this sample (``HELD`` is set too).
REJECTED = 1 << 6
#: A stiffness schedule does not trust its estimate yet (fewer than
#: :data:`fuzzkit.control.adaptation.TRUST_UPDATES` updates since its start or since a sudden
#: stiffening): the gain is its band of ``k_max``, the stiffest contact its range admits.
UNTRUSTED = 1 << 7
#: A stiffness schedule's last update (or a sudden stiffening) read a contact stiffer than its
#: range's ``k_max``: the gain is its most conservative band's.
OUT_OF_RANGE = 1 << 8

#: Every bit by name, in bit order (documentation and generated code list them from here).
BITS: dict[str, int] = {
    "ENGAGED": ENGAGED,
    "HELD": HELD,
    "TRIPPED": TRIPPED,
    "RETREATING": RETREATING,
    "SATURATED": SATURATED,
    "TARING": TARING,
    "REJECTED": REJECTED,
    "UNTRUSTED": UNTRUSTED,
    "OUT_OF_RANGE": OUT_OF_RANGE,
}
#: The bits only a stiffness schedule sets (a controller without one never does).
SCHEDULE_BITS = ("UNTRUSTED", "OUT_OF_RANGE")


def describe(status: int) -> str:
    """``status`` as bit names joined by ``|`` (``"0"`` when none is set)."""
    names = [name for name, bit in BITS.items() if status & bit]
    return "|".join(names) if names else "0"
