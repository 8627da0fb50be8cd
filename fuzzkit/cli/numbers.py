"""The numeric options of every command, checked at the option with their range.

Each numeric option's ``type`` is one :class:`Number` of this module (stiffness and latency,
which have spellings of their own, are :mod:`fuzzkit.cli.units`). A value outside the range,
NaN, an infinity, a fraction where a count is expected or text that is no number is an
argparse error: exit 2, ``argument --seed: expected an integer from 0 to 4294967295, got
'-1'``, before the command reads a file or starts a run. So no bad number reaches a library
that would report it as a bug (``fuzzkit: internal error``). ``tests/test_cli_numbers.py``
walks every command's numeric options, found from the parser, with bad values.

The ranges are those of the code each option feeds; where that code holds the limit as a
constant (a rule view's rule count, a surface's resolution, a table's breakpoints), the test
holds this module's copy equal to it, so that building the parser imports none of that code.
"""

from __future__ import annotations

import argparse
import math
from dataclasses import dataclass

from fuzzkit import units


@dataclass(frozen=True)
class Number:
    """An argparse type: an integer, or a finite real number, in ``[low, high]`` (``(low,
    high]`` with ``low_open``)."""

    integer: bool
    low: float
    high: float
    low_open: bool = False

    @property
    def __name__(self) -> str:  # argparse names a type by it in some messages
        return "integer" if self.integer else "number"

    def expected(self) -> str:
        """What the option takes, as its error message says it."""
        if self.integer:
            return f"an integer from {int(self.low)} to {int(self.high)}"
        left = "(" if self.low_open else "["
        return f"a number in {left}{self.low:g}, {self.high:g}]"

    def __call__(self, text: str) -> int | float:
        value: int | float | None
        try:
            value = int(text.strip()) if self.integer else float(text)
        except ValueError:
            value = None
        if value is None or not self.admits(value):
            raise argparse.ArgumentTypeError(f"expected {self.expected()}, got {text!r}")
        return value

    def admits(self, value: float) -> bool:
        """Whether ``value`` is in the range (NaN and the infinities never are)."""
        if not math.isfinite(value) or value > self.high:
            return False
        return value > self.low if self.low_open else value >= self.low


def integer(low: int, high: int) -> Number:
    """An integer option from ``low`` to ``high``."""
    return Number(True, low, high)


def real(low: float, high: float, low_open: bool = False) -> Number:
    """A finite real option in ``[low, high]`` (``(low, high]`` with ``low_open``)."""
    return Number(False, low, high, low_open)


#: Random seeds (numpy's generators take 0 to 2**32 - 1 as every tool does).
SEED = integer(0, 2**32 - 1)
#: Worker processes of a local pool.
WORKERS = integer(1, 1024)
#: Noise seeds of a sweep, 0..N-1.
SEEDS = integer(1, 10_000)
#: Gain sets a tuning may simulate (``fuzzkit.studies.tuning.optimiser``: 10 at least).
BUDGET = integer(10, 1_000_000)
#: Simulated seconds of a sweep's runs (a scenario file's ``duration_s`` has the same limit).
DURATION_S = real(0.0, units.MAX_DURATION_S, low_open=True)
#: Rules drawn by ``eval --explain --png`` (``fuzzkit.fuzzy.rule_view.MAX_RULES``).
RULES_DRAWN = integer(1, 64)
#: Grid points per input of ``surface`` (``fuzzkit.viz.surface.MAX_RESOLUTION``).
SURFACE_RESOLUTION = integer(2, 1001)
#: Breakpoints per input of ``compile --resolution`` (``fuzzkit.codegen.lookup_table``).
BREAKPOINTS = integer(2, 4096)
#: ``compile --tolerance``: a fraction of each output range.
TOLERANCE = real(0.0, 1.0, low_open=True)
#: ``compile --max-bytes``: the largest table the automatic method takes.
TABLE_BYTES = integer(1, 2**31 - 1)
#: A fraction in (0, 1] (``stability --contact-sector``, ``--fuzzy-region``).
UNIT_FRACTION = real(0.0, 1.0, low_open=True)
#: Periods without a sample before a controller's watchdog stops its output (``fuzzkit ros2``;
#: a spec's ``safety.watchdog.periods`` takes the same, ``control.spec_reader.MAX_SAMPLES``).
WATCHDOG_PERIODS = integer(1, 1_000_000)
