"""The options every command spells alike: ``--stiffness``, ``--latency``, and old spellings.

Each is an argparse ``type`` over :mod:`fuzzkit.units`, so that a
value copied from one command's output or docs works in every other command: stiffness as
``100``, ``100N/mm`` or ``1e5N/m`` (the CLI's own unit is N/mm); latency as ``S:C`` or
``S,C``; several latencies as ``0:0,2:1``. A bad value is an argparse error (exit 2, the
accepted spellings named). ``--png FILE`` is always the figure a command draws and ``--out``
its main output (a table, a gains file, a folder); an old spelling stays as a hidden alias
(:func:`store_alias`).
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any, TypeVar

from fuzzkit import units
from fuzzkit.errors import ConfigError

T = TypeVar("T")

#: Metavars shown in ``--help``, one per option kind.
STIFFNESS_METAVAR = "K"
STIFFNESSES_METAVAR = "K[,K...]"
LATENCY_METAVAR = "S:C"
LATENCIES_METAVAR = "S:C[,S:C...]"
#: The spellings, said once in every ``--help`` that takes them.
STIFFNESS_HELP = "N/mm, or with a unit: 100, 100N/mm, 1e5N/m"
LATENCY_HELP = "sensor:command delays in periods, S:C or S,C"


def _argparse_type(parse: Callable[[str], T], name: str) -> Callable[[str], T]:
    """``parse`` as an argparse type: a ConfigError becomes argparse's own error."""

    def convert(text: str) -> T:
        try:
            return parse(text)
        except ConfigError as exc:
            raise argparse.ArgumentTypeError(str(exc).removeprefix("--latency: ")) from None

    convert.__name__ = name
    return convert


def _modelled(n_per_m: float, text: str) -> float:
    """``n_per_m`` in N/mm, refused outside :data:`fuzzkit.units.STIFFNESS_RANGE_N_PER_M`."""
    low, high = units.STIFFNESS_RANGE_N_PER_M
    if not low <= n_per_m <= high:
        raise ConfigError(
            f"expected a stiffness from {units.stiffness_text(low)} to "
            f"{units.stiffness_text(high)}, the contacts the plants model, got {text.strip()!r}"
        )
    return n_per_m / 1e3


def _stiffness_n_per_mm(text: str) -> float:
    return _modelled(units.parse_stiffness(text), text)


def _stiffnesses_n_per_mm(text: str) -> list[float]:
    pairs = zip(units.parse_stiffnesses(text), text.split(","), strict=True)
    return [_modelled(k, t) for k, t in pairs]


def _latency_pair(text: str) -> tuple[int, int]:
    sensor, command = units.parse_latency(text)
    if command is None:  # parse_latency without sensor_only always gives both
        raise ConfigError(f"expected S:C, got {text!r}")
    return sensor, command


#: One stiffness, in N/mm (``100``, ``100N/mm``, ``1e5N/m``).
stiffness = _argparse_type(_stiffness_n_per_mm, "stiffness")
#: Comma-separated stiffnesses, in N/mm.
stiffnesses = _argparse_type(_stiffnesses_n_per_mm, "stiffnesses")
#: One latency ``S:C`` / ``S,C`` (``S`` alone: the sensor delay; command None).
latency_or_sensor = _argparse_type(lambda t: units.parse_latency(t, sensor_only=True), "latency")
#: One latency pair, ``S:C`` or ``S,C``.
latency = _argparse_type(_latency_pair, "latency")
#: Several latencies: ``0:0,2:1`` (or ``0,0;2,1``, ``"0,0 2,1"``).
latencies = _argparse_type(units.parse_latencies, "latencies")
#: Every option type of this module, which ``tests/test_cli_numbers.py`` walks with the
#: numeric ones of :mod:`fuzzkit.cli.numbers`.
OPTION_TYPES = (stiffness, stiffnesses, latency_or_sensor, latency, latencies)


#: A run's sensor and command delays together may be at most this fraction of its duration:
#: beyond it the loop acts on samples older than half the run, and a run can end before a
#: correction computed from its contact ever reaches the robot.
LATENCY_RUN_FRACTION = 0.5


def check_latency_fits(
    latency: tuple[int, int] | None, exp: Any, duration_s: float | None = None
) -> None:
    """Refuse ``--latency`` when its delays are longer than :data:`LATENCY_RUN_FRACTION` of
    the run of ``exp`` (an :class:`~fuzzkit.loop.task.Experiment`; ``duration_s``: the run's
    length when not the scenario's), naming the range.

    Raises
    ------
    ConfigError
        The delays, in periods and seconds, and the most the run takes.
    """
    if latency is None:
        return
    period = exp.scenario.period_s
    duration = exp.scenario.duration_s if duration_s is None else duration_s
    most = int(LATENCY_RUN_FRACTION * duration / period + 1e-9)
    total = latency[0] + latency[1]
    if total > most:
        raise ConfigError(
            f"--latency {units.latency_text(latency)}: {total} periods of delay "
            f"({total * period:g} s) is more than half of {exp.name}'s {duration:g} s run; "
            f"sensor + command delays may be 0 to {most} periods ({most * period:g} s) there"
        )


def store_alias(parser: argparse.ArgumentParser, *flags: str, dest: str, **kw: Any) -> None:
    """An old spelling of an option, kept working and hidden from ``--help``."""
    parser.add_argument(*flags, dest=dest, help=argparse.SUPPRESS, **kw)
