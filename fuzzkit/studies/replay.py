"""Replay a recorded wrist-sensor log through a controller: the check of generated code against
a user's own robot (``fuzzkit replay``).

The log is CSV with a header: ``fx,fy,fz`` (N, task frame) required, ``t`` (s) and the nine
rotation entries ``r11,r12,...,r33`` (row-major, world-from-sensor) optional, in any order. An
empty cell or a NaN in any spelling C's printf writes (``nan``, ``-nan``, ``NaN``,
``-nan(ind)``) is a missing sample; ``inf`` and ``-inf`` are infinite samples. Reading is
strict: every problem is reported as ``file:line:col`` at once
(:class:`~fuzzkit.errors.ProblemsError`). The output CSV has ``t`` (when the log has it),
``ux,uy,uz`` (m) and ``status`` per row.

A run's CSV (``fuzzkit simulate --csv``, :mod:`fuzzkit.studies.run_table`) is read as it is:
its ``t_s`` is the time, ``f<a>_measured_n`` the sample the controller received (after the
sensor's latency; NaN when none), its rotation columns when it has them, its ``u<a>_m`` the
corrections the run's controller returned and its ``status_bits`` the status it returned
(:attr:`SensorLog.recorded`, :attr:`SensorLog.recorded_status`), which the replay is compared
with (:func:`reproduction`): the status bits exactly, the corrections within
:data:`REPRODUCTION_RTOL` of their largest magnitude, so that a controller whose gains differ
by 1e-10 of their value does not reproduce the run.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, NoReturn

import numpy as np
import numpy.typing as npt

from fuzzkit.control.spec import ControllerSpec
from fuzzkit.errors import ConfigError, Location, Problem, ProblemsError
from fuzzkit.loop.spec import CONTROLLER_IMPLS

if TYPE_CHECKING:
    from fuzzkit.studies.param_schedule import Change

FloatArray = npt.NDArray[np.float64]

FORCE_COLUMNS = ("fx", "fy", "fz")
ROTATION_COLUMNS = tuple(f"r{i}{j}" for i in range(1, 4) for j in range(1, 4))
COLUMNS = ("t", *FORCE_COLUMNS, *ROTATION_COLUMNS)
#: ``--impl``: ``--controller-impl``'s names (``fuzzkit.loop.spec.CONTROLLER_IMPLS``): the
#: generated controller (``auto``: C where it compiles, else Python; ``c``; ``python``), or
#: fuzzkit's ``reference`` controller, asked for by name.
IMPLS = CONTROLLER_IMPLS
#: The generated implementations ``--compare`` holds to the reference.
GENERATED = ("python", "c")
#: What each implementation is, as ``replay`` prints it.
IMPL_LABELS = {"python": "generated Python", "c": "generated C", "reference": "reference"}
#: A number as the log may write it (no thousands separators, no quotes).
_NUMBER = re.compile(r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?|[+-]?inf(?:inity)?", re.I)
#: NaN as C's printf (``nan``, ``-nan``), MSVC (``-nan(ind)``) and others write it, any case.
_NAN = re.compile(r"[+-]?nan(?:\([\w]*\))?", re.I)
#: Problems listed before the reader stops (a wrong file would list every row).
MAX_PROBLEMS = 20


#: A run CSV's columns (``fuzzkit.studies.run_table``) and what they are to the replay.
RUN_TIME = "t_s"
RUN_FORCES = tuple(f"f{a}_measured_n" for a in "xyz")
RUN_CORRECTIONS = tuple(f"u{a}_m" for a in "xyz")
RUN_STATUS_BITS = "status_bits"
_RUN_OTHER = re.compile(r"f[xyz]_(true|setpoint)_n|d?e[xyz]_n|du[xyz]_m|status")
#: How far a replay's corrections may be from the run's, as a fraction of the run's largest
#: ``|u|``: the reference and the generated code are one arithmetic, whose sums of thousands of
#: periods were measured within 2e-15 of it apart (tests/test_user_specs.py's runs); a gain
#: 1e-10 off its value is 100 times this.
REPRODUCTION_RTOL = 1e-12


@dataclass(frozen=True)
class SensorLog:
    """A log read from CSV: forces ``(n, 3)``, rotations ``(n, 9)`` or None, times or None;
    ``recorded``: a run CSV's corrections ``(n, 3)`` (m), ``recorded_status`` its status bits
    ``(n,)``; None for a plain sensor log (and for the status of a run CSV without them)."""

    forces: FloatArray
    rotations: FloatArray | None
    times: FloatArray | None
    recorded: FloatArray | None = None
    recorded_status: npt.NDArray[np.int64] | None = None


def _cells(line: str) -> list[tuple[str, int]]:
    """The comma-separated cells of ``line`` with the 1-based column where each starts."""
    out = []
    col = 1
    for raw in line.split(","):
        stripped = raw.strip()
        lead = len(raw) - len(raw.lstrip())
        out.append((stripped, col + lead))
        col += len(raw) + 1
    return out


def raise_sorted(problems: list[Problem]) -> NoReturn:
    """Raise the problems sorted by line and column, the first :data:`MAX_PROBLEMS` of them
    (with a last line saying the reader stopped, when there were more)."""
    ordered = sorted(problems, key=lambda p: (p.location.line, p.location.col))
    if len(ordered) <= MAX_PROBLEMS:
        raise ProblemsError(ordered)
    shown = ordered[:MAX_PROBLEMS]
    raise ProblemsError(
        shown,
        f"{MAX_PROBLEMS} problems listed (the reader stopped there; fix these and read again)",
    )


def read_sensor_log(path: str | Path) -> SensorLog:
    """Read a sensor log (see the module docstring).

    Raises
    ------
    ProblemsError
        Every problem with its ``file:line:col``: no header, unknown or repeated columns,
        ``fx,fy,fz`` missing, some but not all rotation columns, a row with the wrong number
        of cells, a cell that is not a number, a missing or non-increasing time; a file
        that cannot be read (missing, a folder), at the file's name.
    """
    name = str(path)
    try:
        data = Path(path).read_bytes()  # not size-capped: a long log is many megabytes
    except IsADirectoryError:
        raise ProblemsError(
            [Problem(Location(name), "is a directory (expected a CSV file)")]
        ) from None
    except OSError as exc:
        raise ProblemsError(
            [Problem(Location(name), f"cannot read: {exc.strerror or exc}")]
        ) from None
    problems: list[Problem] = []

    def bad(line: int, col: int, message: str) -> None:
        problems.append(Problem(Location(name, line, col), message))

    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        where = data[: exc.start].count(b"\n") + 1
        raise ProblemsError([Problem(Location(name, where), "not UTF-8 text")]) from None
    lines = text.splitlines()
    if not lines or not lines[0].strip():
        raise ProblemsError(
            [Problem(Location(name, 1, 1), "expected a header row (fx,fy,fz[,t][,r11..r33])")]
        )
    header = _cells(lines[0])
    keys = [cell.lower() for cell, _ in header]
    run = RUN_TIME in keys and all(c in keys for c in RUN_FORCES)
    index: dict[str, int] = {}
    recorded_at: dict[int, int] = {}  # axis -> column of a run's u<a>_m
    status_at: int | None = None  # column of a run's status_bits
    ignored: set[int] = set()  # a run's other columns (text in status)
    for k, (cell, col) in enumerate(header):
        key = cell.lower()
        if run:
            if key == RUN_TIME:
                key = "t"
            elif key in RUN_FORCES:
                key = FORCE_COLUMNS[RUN_FORCES.index(key)]
            elif key in RUN_CORRECTIONS and RUN_CORRECTIONS.index(key) not in recorded_at:
                recorded_at[RUN_CORRECTIONS.index(key)] = k
                continue
            elif key == RUN_STATUS_BITS and status_at is None:
                status_at = k
                continue
            elif _RUN_OTHER.fullmatch(key):
                ignored.add(k)
                continue
        if key not in COLUMNS:
            bad(1, col, f"unknown column {cell!r} (expected {', '.join(COLUMNS)})")
        elif key in index:
            bad(1, col, f"column {cell!r} appears twice")
        else:
            index[key] = k
    for col_name in FORCE_COLUMNS:
        if col_name not in index:
            bad(1, 1, f"column {col_name!r} is missing (fx, fy, fz are required)")
    rot_given = [c for c in ROTATION_COLUMNS if c in index]
    if rot_given and len(rot_given) != 9:
        missing = [c for c in ROTATION_COLUMNS if c not in index]
        bad(1, 1, f"rotation columns incomplete: {', '.join(missing)} missing (all 9 or none)")
    if problems:  # every problem of the header, however many: each names one column
        raise ProblemsError(sorted(problems, key=lambda p: (p.location.line, p.location.col)))
    rows: list[list[float]] = []
    row_lines: list[int] = []  # the file line of each row kept (rows with problems are not)
    width = len(header)
    for n, line in enumerate(lines[1:], start=2):
        if not line.strip():
            if all(not rest.strip() for rest in lines[n - 1 :]):
                break  # trailing blank lines
            bad(n, 1, "blank line inside the log (a missing sample is a row of empty cells)")
            continue
        cells = _cells(line)
        if len(cells) != width:
            bad(n, len(line) + 1, f"expected {width} cells (as the header), got {len(cells)}")
            continue
        row = []
        for k, (cell, col) in enumerate(cells):
            if k == status_at and not (cell.isdigit() and int(cell) < 2**31):
                bad(n, col, f"expected the status bits as a whole number, got {cell!r}")
                row.append(math.nan)
            elif k in ignored or not cell or _NAN.fullmatch(cell):
                row.append(math.nan)
            elif _NUMBER.fullmatch(cell):
                row.append(float(cell))
            else:
                bad(n, col, f"expected a number, an empty cell or nan, got {cell!r}")
                row.append(math.nan)
        rows.append(row)
        row_lines.append(n)
        if len(problems) > MAX_PROBLEMS:
            break
    if not rows and not problems:
        bad(2, 1, "the log has a header but no rows")
    values = np.array(rows, dtype=np.float64).reshape(len(rows), width)
    times = None
    if "t" in index:
        times = values[:, index["t"]]
        t_col = header[index["t"]][1]
        last = math.nan  # the last finite time, on the last row kept
        for k, t in enumerate(times.tolist()):
            if not math.isfinite(t):
                bad(row_lines[k], t_col, "t must be a finite time (s)")
                continue
            if math.isfinite(last) and t <= last:
                bad(row_lines[k], t_col, f"t must increase (got {t:g} s after {last:g} s)")
            last = t
    if problems:
        raise_sorted(problems)
    forces = values[:, [index[c] for c in FORCE_COLUMNS]]
    rotations = values[:, [index[c] for c in ROTATION_COLUMNS]] if rot_given else None
    recorded = None
    if run and len(recorded_at) == 3:
        recorded = np.ascontiguousarray(values[:, [recorded_at[i] for i in range(3)]])
    status = None
    if run and status_at is not None:
        status = values[:, status_at].astype(np.int64)
    return SensorLog(np.ascontiguousarray(forces), rotations, times, recorded, status)


def replay(
    spec: ControllerSpec,
    log: SensorLog,
    impl: str = "auto",
    number_type: str = "double",
    schedule: Sequence[Change] = (),
) -> tuple[FloatArray, npt.NDArray[np.int64]]:
    """Run the controller of ``spec`` on ``log`` from reset: corrections ``(n, 3)`` and status.

    ``impl`` (:data:`IMPLS`): the spec's generated controller, ``c`` compiled and called
    through ctypes (``number_type`` float/double), ``python`` the generated Python module
    (``NAME_controller.py``) imported and run, ``auto`` (default) the C where it compiles, else
    the Python (:func:`replayed_by` says which); or ``reference``, fuzzkit's reference
    controller (``fuzzkit.control.reference``). ``schedule``: parameter changes
    (:mod:`fuzzkit.studies.param_schedule`), for the reference only.
    """
    out, status, _ = replayed_by(spec, log, impl, number_type, schedule)
    return out, status


def replayed_by(
    spec: ControllerSpec,
    log: SensorLog,
    impl: str = "auto",
    number_type: str = "double",
    schedule: Sequence[Change] = (),
) -> tuple[FloatArray, npt.NDArray[np.int64], str]:
    """:func:`replay`, and the implementation that ran (``c``, ``python`` or ``reference``:
    what ``auto`` became)."""
    if impl not in IMPLS:
        raise ConfigError(f"unknown --impl {impl!r} (expected one of {', '.join(IMPLS)})")
    if schedule and impl != "reference":
        raise ConfigError(
            "--schedule changes the reference's parameters (--impl reference); the generated "
            "controller has them built in (the FMU's are tunable: docs/fmu.md)"
        )
    if impl == "reference":
        from fuzzkit.control.reference import Controller
        from fuzzkit.loop.controller_code import spec_surface
        from fuzzkit.studies.param_schedule import apply

        ref = Controller(spec, spec_surface(spec) if spec.kind == "fuzzy-pi" else None)
        n = log.forces.shape[0]
        out = np.empty((n, 3))
        status = np.zeros(n, dtype=np.int64)
        rot = None if log.rotations is None else log.rotations.tolist()
        by_period: dict[int, list[Change]] = {}
        for change in schedule:
            by_period.setdefault(change.period, []).append(change)
        for k, force in enumerate(log.forces.tolist()):
            if k in by_period:
                apply(ref, by_period[k])
            out[k], status[k] = ref.step(force, None if rot is None else rot[k])
        return out, status, impl
    from fuzzkit.loop.generated import open_generated_impl

    target, ctl = open_generated_impl(spec, impl, number_type)
    result: tuple[FloatArray, npt.NDArray[np.int64]] = ctl.run(log.forces, log.rotations)
    return result[0], result[1], target


@dataclass(frozen=True)
class Difference:
    """How far one implementation's replay is from the reference's: the largest ``|du|`` per
    axis (m) and the rows whose status differs."""

    impl: str
    largest_m: tuple[float, float, float]
    status_rows: int


def compare(
    spec: ControllerSpec, log: SensorLog, number_type: str = "double"
) -> tuple[tuple[FloatArray, npt.NDArray[np.int64]], list[Difference]]:
    """Replay ``log`` through every implementation: the reference's output, and each generated
    one's :class:`Difference` from it (``fuzzkit replay --compare``)."""
    ref_out, ref_status = replay(spec, log, "reference")
    diffs = []
    for impl in GENERATED:
        out, status = replay(spec, log, impl, number_type)
        gap = np.abs(out - ref_out).max(axis=0) if out.size else np.zeros(3)
        diffs.append(
            Difference(
                impl,
                (float(gap[0]), float(gap[1]), float(gap[2])),
                int(np.count_nonzero(status != ref_status)),
            )
        )
    return (ref_out, ref_status), diffs


@dataclass(frozen=True)
class Reproduction:
    """How a replay of a run's CSV compares with the run: the largest ``|u - u_run|``, what
    :data:`REPRODUCTION_RTOL` allows, and the rows whose status bits differ (None: the CSV has
    no ``status_bits``)."""

    largest_m: float
    allowed_m: float
    status_rows: int | None
    first_status_row: int | None

    @property
    def ok(self) -> bool:
        """The replay reproduces the run: corrections within the tolerance, same status."""
        return self.largest_m <= self.allowed_m and not self.status_rows

    def lines(self) -> list[str]:
        """What ``fuzzkit replay`` prints about it."""
        out = [
            f"largest difference from the run's corrections (u<a>_m): {self.largest_m:.3g} m "
            f"(allowed {self.allowed_m:.3g} m: {REPRODUCTION_RTOL:g} of the largest |u|)"
        ]
        if self.status_rows is None:
            out.append("status bits: the run's CSV has none (status_bits), not compared")
        elif self.status_rows:
            rows = "1 row differs" if self.status_rows == 1 else f"{self.status_rows} rows differ"
            out.append(
                f"status bits: {rows} from the run's, the first at period {self.first_status_row}"
            )
        else:
            out.append("status bits: equal to the run's in every row")
        verdict = "reproduces the run" if self.ok else "DOES NOT reproduce the run"
        out.append(f"replay: {verdict}")
        return out


def reproduction(
    out: FloatArray, status: npt.NDArray[np.int64], log: SensorLog
) -> Reproduction | None:
    """How the replay ``out``, ``status`` of ``log`` compares with the run it was read from
    (None for a plain sensor log, which records no corrections)."""
    if log.recorded is None:
        return None
    n = out.shape[0]
    largest = float(np.max(np.abs(out - log.recorded))) if n else 0.0
    scale = float(np.max(np.abs(log.recorded))) if n else 0.0
    rows = first = None
    if log.recorded_status is not None:
        differ = np.flatnonzero(status != log.recorded_status)
        rows = int(differ.size)
        first = int(differ[0]) if differ.size else None
    return Reproduction(largest, REPRODUCTION_RTOL * scale, rows, first)


def replay_csv(
    times: FloatArray | None,
    out: FloatArray,
    status: npt.NDArray[np.int64],
    status_names: bool = False,
) -> str:
    """The output CSV: ``[t,]ux,uy,uz,status`` per row (numbers as Python writes them back
    exactly); with ``status_names`` the status column holds the set bits' names joined by
    ``|`` (``ENGAGED|SATURATED``; ``0`` when none is set) instead of the integer."""
    from fuzzkit.control.status import describe

    head = ("t," if times is not None else "") + "ux,uy,uz,status"
    lines = [head]
    for k in range(out.shape[0]):
        t = f"{float(times[k])!r}," if times is not None else ""
        u = ",".join(repr(float(v)) for v in out[k])
        code = int(status[k])
        lines.append(f"{t}{u},{describe(code) if status_names else code}")
    return "\n".join(lines) + "\n"
