"""One spelling per quantity: contact stiffness with its unit, latency as sensor:command periods.

Every command line option and every file that gives a stiffness or a latency reads it here,
so ``100``, ``100N/mm`` and ``1e5 N/m`` mean the same thing everywhere, and ``2:1`` and
``2,1`` both mean "2 periods of sensor delay, 1 of command delay". Printed, a latency is
always ``S:C`` (:func:`latency_text`). This module sits at the bottom of the layering (it
imports only :mod:`fuzzkit.errors`), so the scenario reader and the CLI share it.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence

from fuzzkit.errors import ConfigError

#: The longest run a scenario file or ``--duration`` may ask for, in simulated seconds, and
#: the longest sensor or command delay, in periods (docs/simulation.md, "Scenario files").
MAX_DURATION_S = 600.0
MAX_LATENCY_PERIODS = 1000

#: The contact stiffnesses a command line option takes, in N/m: 0.1 N/mm (a foam pad) to
#: 10,000 N/mm (a steel fixture). The kit's studies span 1 to 1000 N/mm; far outside, the
#: penalty contact of the plants is no model of anything (1e12 N/mm gives forces of 1e11 N).
STIFFNESS_RANGE_N_PER_M = (1e2, 1e7)

#: Stiffness units accepted after a number (case-insensitive), as N/m per unit.
STIFFNESS_UNITS: dict[str, float] = {"n/mm": 1e3, "n/m": 1.0, "kn/m": 1e3}

_QUANTITY = re.compile(r"^\s*([-+0-9.eE]+|[-+]?(?:nan|inf(?:inity)?))\s*([A-Za-z/]*)\s*$", re.I)


def parse_stiffness(text: str, unit: str = "N/mm") -> float:
    """A contact stiffness in N/m from ``text``: a number in ``unit`` (the place's own unit,
    ``N/mm`` on the command line), or a number with a unit (``100N/mm``, ``1e5 N/m``).

    Raises
    ------
    ConfigError
        Not a number, an unknown unit, or a value that is not finite and > 0 (the message
        names the accepted spellings).
    """
    shown = text.strip()
    match = _QUANTITY.match(text)
    scale = None
    value = math.nan
    if match:
        try:
            value = float(match.group(1))
        except ValueError:
            value = math.nan
        scale = STIFFNESS_UNITS.get((match.group(2) or unit).lower())
    if scale is None or not (math.isfinite(value) and value > 0.0):
        raise ConfigError(
            f"expected a stiffness > 0: a number in {unit} or with its unit "
            f"(100, 100N/mm, 1e5N/m), got {shown!r}"
        )
    return value * scale


def parse_stiffnesses(text: str, unit: str = "N/mm") -> list[float]:
    """Comma-separated stiffnesses (:func:`parse_stiffness` each) in N/m."""
    items = text.split(",")
    if not text.strip() or any(not t.strip() for t in items):
        raise ConfigError(
            f"expected comma-separated stiffnesses (5,10,20 in {unit}, or 5N/mm,1e4N/m), "
            f"got {text!r}"
        )
    return [parse_stiffness(t, unit) for t in items]


def stiffness_text(n_per_m: float) -> str:
    """A stiffness as printed: ``10 N/mm``."""
    return f"{n_per_m / 1e3:g} N/mm"


_PAIR = re.compile(r"^\s*(\d+)\s*(?:[:,]\s*(\d+)\s*)?$")
_LATENCY_HELP = (
    f"SENSOR:COMMAND (or SENSOR,COMMAND) delays in periods, integers 0 to {MAX_LATENCY_PERIODS}"
)


def _delays(match: re.Match[str] | None) -> tuple[int, int | None] | None:
    """The two delays of a matched pair (the second None when not given), or None when
    there is no match or a delay is above :data:`MAX_LATENCY_PERIODS`."""
    if match is None:
        return None
    sensor, command = int(match.group(1)), match.group(2)
    pair = sensor, None if command is None else int(command)
    return None if max(d or 0 for d in pair) > MAX_LATENCY_PERIODS else pair


def parse_latency(text: str, sensor_only: bool = False) -> tuple[int, int | None]:
    """``"2:1"`` or ``"2,1"`` -> ``(2, 1)``: sensor and command delays in periods.

    With ``sensor_only``, one number is accepted too and sets the sensor delay alone
    (``(2, None)``: the command delay is the scenario's).

    Raises
    ------
    ConfigError
        Anything else (the message shows the accepted spellings).
    """
    pair = _delays(_PAIR.match(text))
    if pair is None or (pair[1] is None and not sensor_only):
        one = " (or one number: the sensor delay alone)" if sensor_only else ""
        raise ConfigError(f"--latency: expected {_LATENCY_HELP}{one}, got {text!r}")
    return pair


def parse_latencies(text: str) -> list[tuple[int, int]]:
    """A list of latencies: ``0:0,2:1`` (pairs written S:C, separated by commas), or pairs
    written either way separated by spaces or semicolons (``0,0 2,1``, ``0,0;2,1``); a lone
    ``2,1`` is one pair.

    Raises
    ------
    ConfigError
        An item that is no pair of integers >= 0, or an empty list.
    """
    stripped = text.strip()
    if re.search(r"[;\s]", stripped):
        items = [t for t in re.split(r"[;\s]+", stripped) if t]
    elif ":" in stripped:
        items = stripped.split(",")
    else:
        items = [stripped]
    out: list[tuple[int, int]] = []
    for item in items:
        pair = _delays(_PAIR.match(item))
        if pair is None or pair[1] is None:
            raise ConfigError(
                f"--latency: expected {_LATENCY_HELP}, several as 0:0,2:1 (got {item!r} in "
                f"{text!r})"
            )
        out.append((pair[0], pair[1]))
    return out


def latency_text(latency: Sequence[int]) -> str:
    """A latency as printed everywhere: ``S:C`` (sensor:command periods)."""
    sensor, command = latency
    return f"{sensor}:{command}"


def latencies_text(latencies: Sequence[Sequence[int]]) -> str:
    """Several latencies as one option would take them: ``0:0,1:1``."""
    return ",".join(latency_text(p) for p in latencies)
