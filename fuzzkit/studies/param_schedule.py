"""Parameter changes during a replay (``fuzzkit replay --schedule``): what the FMU's tunable
parameters and its ``tare`` and ``reset`` inputs do in a co-simulation, given as a file.

The schedule is CSV with the header ``period,name,value``: before the log's sample ``period``
(0-based) the parameter ``name`` takes ``value``. The names are the FMU's
(:func:`parameter_names`): per force-controlled axis ``kp_A``, ``ki_A``, ``kx_A`` (fuzzy-PI)
and ``setpoint_A`` (N), and ``limit_n`` (N); and the events ``tare`` and ``reset`` (value 1).
Within one period the parameters are set first, then ``reset`` (which keeps them), then
``tare``, as the FMU's ``fmi2DoStep`` takes them. Values are checked as the reference
controller checks the spec's: finite, fuzzy-PI gains > 0, PI gains >= 0, the limit > 0, and
every set point's size and the engagement threshold below the limit after each change.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from fuzzkit.control.names import GAIN_KEYS
from fuzzkit.control.spec import ControllerSpec
from fuzzkit.errors import Location, Problem, ProblemsError, did_you_mean

#: Events, in the order they act within one period (after the parameters).
EVENTS = ("reset", "tare")


def parameter_names(spec: ControllerSpec) -> tuple[str, ...]:
    """The tunable parameters of ``spec``'s FMU, in its modelDescription's order."""
    gains = GAIN_KEYS[spec.kind]
    names = []
    for a in sorted(spec.axes, key=lambda a: a.index):
        names += [f"{g}_{a.axis}" for g in gains] + [f"setpoint_{a.axis}"]
    return (*names, "limit_n")


@dataclass(frozen=True)
class Change:
    """``name`` takes ``value`` before sample ``period`` (an event: value 1)."""

    period: int
    name: str
    value: float


def value_problem(spec: ControllerSpec, name: str, value: float) -> str | None:
    """Why ``value`` cannot be ``name``'s (finite; a fuzzy-PI's scaling factors > 0, a PI's
    gains >= 0, the limit > 0, an event 1), or None; ``fuzzkit ros2`` checks its parameters so."""
    if not math.isfinite(value):
        return f"{name} must be a finite number, got {value:g}"
    if name in EVENTS:
        return None if value == 1.0 else f"{name} is an event: its value is 1, got {value:g}"
    if name == "limit_n" and not value > 0.0:
        return f"limit_n must be > 0 (N), got {value:g}"
    if name[:2] in ("kp", "ki", "kx"):
        if spec.kind == "fuzzy-pi" and not value > 0.0:
            return f"{name} must be > 0 (a fuzzy-PI scaling factor), got {value:g}"
        if value < 0.0:
            return f"{name} must be >= 0 (a PI gain), got {value:g}"
    return None


def read_schedule(path: str | Path, spec: ControllerSpec, n_samples: int) -> list[Change]:
    """The changes of the schedule file, ordered as they act (by period, then parameters,
    ``reset``, ``tare``).

    Raises
    ------
    ProblemsError
        Every problem as ``file:line:col``: the header, an unknown name, a period that is not
        an integer in ``[0, n_samples)``, a value that is not a number or that the controller
        refuses.
    """
    name = str(path)
    problems: list[Problem] = []
    lines = Path(path).read_text(encoding="utf-8").splitlines()
    if not lines or [c.strip().lower() for c in lines[0].split(",")] != [
        "period",
        "name",
        "value",
    ]:
        raise ProblemsError(
            [Problem(Location(name, 1, 1), "expected the header period,name,value")]
        )
    known = (*parameter_names(spec), *EVENTS)
    changes: list[tuple[int, int, int, Change]] = []
    for n, line in enumerate(lines[1:], start=2):
        if not line.strip():
            continue
        cells = line.split(",")
        if len(cells) != 3:
            problems.append(Problem(Location(name, n, 1), f"expected 3 cells, got {len(cells)}"))
            continue
        cols = [1, len(cells[0]) + 2, len(cells[0]) + len(cells[1]) + 3]
        period_text, what, value_text = (c.strip() for c in cells)
        try:
            period = int(period_text)
        except ValueError:
            period = -1
        if not 0 <= period < n_samples:
            problems.append(
                Problem(
                    Location(name, n, cols[0]),
                    f"period must be a sample of the log, 0 to {n_samples - 1}, got "
                    f"{period_text!r}",
                )
            )
        if what not in known:
            problems.append(
                Problem(
                    Location(name, n, cols[1]),
                    f"unknown parameter {what!r}{did_you_mean(what, known)} (this spec's: "
                    f"{', '.join(known)})",
                )
            )
            continue
        try:
            value = float(value_text)
        except ValueError:
            problems.append(
                Problem(Location(name, n, cols[2]), f"expected a number, got {value_text!r}")
            )
            continue
        why = value_problem(spec, what, value)
        if why is not None:
            problems.append(Problem(Location(name, n, cols[2]), why))
            continue
        rank = EVENTS.index(what) + 1 if what in EVENTS else 0
        changes.append((period, rank, n, Change(period, what, value)))
    ordered = [(line, c) for _, _, line, c in sorted(changes, key=lambda t: t[:3])]
    problems += _limit_problems(spec, ordered, name)
    if problems:
        raise ProblemsError(sorted(problems, key=lambda p: (p.location.line, p.location.col)))
    return [c for _, c in ordered]


def _limit_problems(
    spec: ControllerSpec, changes: list[tuple[int, Change]], path: str
) -> list[Problem]:
    """The spec's rule kept through the changes: every set point's size and the engagement
    threshold below the safety limit (else the loop trips at rest; the FMU refuses the same)."""
    setpoints = {a.axis: a.setpoint_n for a in spec.axes}
    limit = spec.safety.limit_n
    floor = spec.safety.engage_threshold_n or 0.0
    out = []
    for line, change in changes:
        if change.name == "limit_n":
            limit = change.value
        elif change.name.startswith("setpoint_"):
            setpoints[change.name.removeprefix("setpoint_")] = change.value
        else:
            continue
        biggest = max([abs(v) for v in setpoints.values()] + [floor])
        if biggest >= limit:
            out.append(
                Problem(
                    Location(path, line),
                    f"{change.name} = {change.value:g}: the set points' sizes and the "
                    f"engagement threshold must stay below the safety limit (now "
                    f"{biggest:g} N against {limit:g} N)",
                )
            )
    return out


def apply(controller: object, changes: Iterable[Change]) -> None:
    """Apply ``changes`` to a reference controller (``fuzzkit.control.reference.Controller``)."""
    from fuzzkit.control.names import AXES
    from fuzzkit.control.reference import Controller

    if not isinstance(controller, Controller):
        raise TypeError("a schedule applies to the reference controller")
    hybrid = controller.hybrid
    for change in changes:
        if change.name == "reset":
            controller.reset()
        elif change.name == "tare":
            controller.tare()
        elif change.name == "limit_n":
            hybrid.force_limit_n = change.value
        else:
            what, axis = change.name.rsplit("_", 1)
            i = AXES.index(axis)
            if what == "setpoint":
                hybrid.setpoints[i] = change.value
            else:
                setattr(hybrid.controllers[i], what, change.value)
