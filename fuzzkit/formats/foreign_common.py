"""What the FIS, FCL and FLL importers and exporters share.

A foreign file is read as text with a size limit; each importer records where every part of the
model came from (a *mark* per logical path, as :mod:`fuzzkit.fuzzy.validation` names them) so
that the semantic checks run on the finished model can be reported as ``file:line:col`` too.
Exporters refuse what their format cannot hold (:class:`ExportError`) unless the caller allows
the listed losses.

Shape conversions used by more than one format live here: point lists (FCL's IEC dialect and
FLL's ``Discrete``) to and from fuzzkit's piecewise-linear shapes, and number formatting that
round-trips every float exactly.
"""

from __future__ import annotations

import hashlib
import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path as FsPath
from typing import NoReturn

from fuzzkit.errors import FuzzkitError, Location, Problem, RuleBaseError
from fuzzkit.fuzzy import shapes, validation
from fuzzkit.fuzzy.model import (
    SUGENO_SHAPES,
    Compound,
    Expression,
    Proposition,
    RuleBase,
    Source,
    Term,
)
from fuzzkit.fuzzy.validation import Path
from fuzzkit.located_yaml import DocumentKind, read_text_file

#: Defuzzifiers of Sugeno rule bases.
SUGENO_DEFUZZIFIERS = frozenset({"weighted_average", "weighted_sum"})


class ExportError(FuzzkitError, ValueError):
    """A rule base holds something the target format cannot express; every item is listed."""

    def __init__(self, fmt: str, name: str, items: Sequence[str], hint: str = "") -> None:
        self.items = tuple(items)
        lines = "\n".join(f"  - {item}" for item in self.items)
        super().__init__(
            f"{name}: cannot export to {fmt} without changing its meaning:\n{lines}"
            + (f"\n{hint}" if hint else "")
        )


@dataclass(frozen=True)
class ForeignFormat:
    """One foreign rule-base format, as its module declares it (``FORMAT``) and
    :data:`fuzzkit.formats.registry.FORMATS` lists it: every command reads and writes it
    through this record.

    ``name``: ``--format`` and :func:`fuzzkit.fuzzy.shapes.spellings` key it. ``suffix``: the
    file extension every command reads it by. ``label``: the format in help and messages.
    ``first_word``: the first word of its text, by which ``fuzzkit validate`` recognises it.
    ``read(path)``: the rule base and its warnings. ``write(rb, allow_loss, dialect)``: its
    text (``dialects``: the dialects it writes, the first the default; () when it has none).
    ``losses(rb)``: what writing it would change (exported only with ``--allow-loss``), and
    ``meaning``: whose semantics then apply ("MATLAB's").
    """

    name: str
    suffix: str
    label: str
    first_word: str
    read: Callable[[FsPath], tuple[RuleBase, list[Problem]]]
    write: Callable[[RuleBase, bool, str], str]
    losses: Callable[[RuleBase], list[str]] = lambda _rb: []
    meaning: str = ""
    dialects: tuple[str, ...] = ()


def is_sugeno(rb: RuleBase) -> bool:
    """True when the rule base's outputs are Sugeno terms (constant or linear)."""
    return any(t.shape in SUGENO_SHAPES for v in rb.outputs for t in v.terms)


@dataclass
class Collector:
    """Problems found while reading one file, and where each part of the model came from."""

    source: str
    problems: list[Problem] = field(default_factory=list)
    marks: dict[Path, Location] = field(default_factory=dict)

    def at(self, line: int, col: int = 0) -> Location:
        return Location(self.source, line, col)

    def add(self, line: int, col: int, message: str) -> None:
        self.problems.append(Problem(self.at(line, col), message))

    def mark(self, path: Path, line: int, col: int = 0) -> None:
        self.marks.setdefault(path, self.at(line, col))

    def locate(self, path: Path) -> Location:
        """The mark of the longest prefix of ``path`` that has one (the file if none)."""
        for n in range(len(path), -1, -1):
            loc = self.marks.get(path[:n])
            if loc is not None:
                return loc
        return Location(self.source)

    def raise_if_any(self) -> None:
        if self.problems:
            self.fail()

    def fail(self) -> NoReturn:
        """Raise the problems gathered so far (there must be at least one)."""
        unique = list(dict.fromkeys(self.problems))
        unique.sort(key=lambda p: (p.location.line, p.location.col))
        raise RuleBaseError(unique)


def finish(rb: RuleBase, found: Collector, text: str) -> tuple[RuleBase, list[Problem]]:
    """Check ``rb`` semantically, report every problem located in the file, attach its source.

    Imported systems get ``coverage: allow_gaps``: many published ones (MATLAB's tipper among
    them) have input values where no term is above zero, and their tools evaluate them anyway
    (the output's default there). A gap is returned as a located warning, which ``fuzzkit
    validate`` prints and ``--strict`` makes an error.

    Raises
    ------
    RuleBaseError
        Listing the reader's problems and the semantic ones, sorted by position.
    """
    rb = replace(rb, coverage="allow_gaps")
    found_issues = validation.diagnose(rb)
    for path, message in found_issues.errors:
        found.problems.append(
            Problem(found.locate(path), f"{validation.format_path(path)}: {message}")
        )
    found.raise_if_any()
    warnings = [
        Problem(found.locate(path), f"{validation.format_path(path)}: {message}", "warning")
        for path, message in found_issues.warnings
    ]
    digest = hashlib.sha256(text.encode("utf-8")).hexdigest()
    return replace(rb, source=Source(found.source, digest)), warnings


#: What a foreign rule-base file is, for the messages of the shared file reading.
FOREIGN_DOCUMENT = DocumentKind("rule base", "rule bases", "expected a rule base", RuleBaseError)


def read_text(path: str | FsPath, what: str) -> str:
    """The UTF-8 text of a rule-base file ``what`` (e.g. ``a .fis file``), size-checked; a
    byte-order mark is dropped (MATLAB on Windows writes one)."""
    return read_text_file(path, FOREIGN_DOCUMENT, what, encoding="utf-8-sig")


def parse_number(token: str) -> float | None:
    """``token`` as a float (``inf``, ``-inf`` and ``nan`` in any case), or None if it is not."""
    if "_" in token:  # Python's float() reads "1_000"; no rule-base format does
        return None
    try:
        value = float(token)
    except ValueError:
        return None
    return value


def fmt(x: float) -> str:
    """Shortest text that reads back as exactly ``x``: ``1``, ``0.25``, ``-inf``, ``nan``."""
    x = float(x)
    if math.isnan(x):
        return "nan"
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    if x.is_integer() and abs(x) < 1e16:
        return str(int(x))
    return repr(x)


# ---------------------------------------------------------------------------- point lists


def points_to_term(name: str, points: Sequence[tuple[float, float]]) -> Term | str:
    """A point list (membership held constant beyond its ends) as a fuzzkit term, or why not.

    Exactly the lists that draw a triangle, trapezoid or shoulder are accepted: x increasing,
    every y 0 or 1, the 1s consecutive; repeated end values are dropped (``(0,1) (2,1) (4,0)``
    is a left shoulder from 2 to 4). A single point ``(x, 1)`` stands for a singleton.
    """
    xs = [p[0] for p in points]
    ys = [p[1] for p in points]
    if not points:
        return "a point list needs at least one point"
    if any(not math.isfinite(v) for v in xs + ys):
        return "point coordinates must be finite numbers"
    if any(b < a for a, b in itertools.pairwise(xs)):
        return f"point x values must not decrease, got {', '.join(fmt(x) for x in xs)}"
    if any(y not in (0.0, 1.0) for y in ys):
        return (
            "only point lists with memberships 0 and 1 (a triangle, trapezoid or shoulder) "
            f"are exact in fuzzkit, got memberships {', '.join(fmt(y) for y in ys)}"
        )
    if len(points) == 1:
        return (
            Term(name, "singleton", (xs[0],)) if ys[0] == 1.0 else "a single point must be (x, 1)"
        )
    # membership is constant beyond the ends: repeated values there carry no shape
    while len(ys) > 1 and ys[0] == ys[1]:
        xs, ys = xs[1:], ys[1:]
    while len(ys) > 1 and ys[-1] == ys[-2]:
        xs, ys = xs[:-1], ys[:-1]
    pattern = tuple(int(y) for y in ys)
    shapes = {
        (0, 1, 0): "triangle",
        (0, 1, 1, 0): "trapezoid",
        (1, 0): "left_shoulder",
        (0, 1): "right_shoulder",
    }
    shape = shapes.get(pattern)
    if shape is None:
        return (
            "the points do not draw a triangle (0 1 0), trapezoid (0 1 1 0) or shoulder "
            f"(1 0 or 0 1); memberships {' '.join(map(str, pattern))}"
        )
    return Term(name, shape, tuple(xs))


def term_to_points(term: Term) -> list[tuple[float, float]] | None:
    """A piecewise-linear term as a point list (constant beyond its ends), else None."""
    points = shapes.shape(term.shape).points
    return None if points is None else points(term.params)


# ---------------------------------------------------------------------------- named shapes


def read_named(
    file_format: shapes.Format, name: str, kind: str, values: Sequence[float]
) -> Term | str:
    """The term ``file_format`` writes as ``kind values`` (a name it spells, with its arity),
    or why not.

    Which shape and parameter order a name means is the shape registry's
    (:func:`fuzzkit.fuzzy.shapes.read_term`): MATLAB's ``trapmf`` with ``-inf -inf`` feet is a
    left shoulder, fuzzylite's ``Ramp`` a left or right shoulder by its direction.
    """
    found = shapes.read_term(file_format, kind, values)
    if isinstance(found, str):
        return found
    return Term(name, *found)


def write_named(file_format: shapes.Format, term: Term) -> str | None:
    """``kind p1 p2 ...`` as ``file_format`` writes ``term``; None if it has no name for it."""
    found = shapes.write_term(file_format, term.shape, term.params)
    if found is None:
        return None
    kind, params = found
    return " ".join([kind, *map(fmt, params)])


# ---------------------------------------------------------------------------- rules


def combine(op: str, operands: Sequence[Expression]) -> Expression:
    """One proposition as itself, several as an ``and``/``or`` compound."""
    if len(operands) == 1:
        return operands[0]
    return Compound("and" if op == "and" else "or", tuple(operands))


def flat_conditions(expr: Expression) -> tuple[str, list[Proposition]] | None:
    """A flat AND/OR of propositions as ``(op, propositions)``; None for nested expressions."""
    if isinstance(expr, Proposition):
        return "and", [expr]
    props = [e for e in expr.operands if isinstance(e, Proposition)]
    if len(props) != len(expr.operands):
        return None
    return expr.op, props
