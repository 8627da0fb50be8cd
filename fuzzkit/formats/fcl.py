"""IEC 61131-7 Fuzzy Control Language (``.fcl``): import to and export from fuzzkit's model.

Both dialects are read: IEC point lists (``TERM warm := (10, 0) (20, 1) (30, 0);``, the
membership held constant beyond the first and last points, exact when they draw a triangle,
trapezoid or shoulder) and the named shapes fuzzylite and jFuzzyLogic write
(``TERM warm := Triangle 10 20 30;``, every shape fuzzylite names, the smooth ``SShape``,
``ZShape``, ``PiShape``, ``GaussianProduct``, ``SigmoidDifference`` and ``SigmoidProduct``
among them; jFuzzyLogic's ``trian``, ``trape``, ``gauss``, ``gauss2``, ``gbell`` and ``sigm``
too, as the shape registry spells them). A bare number is a singleton (an input) or a Sugeno
constant (an output). The IEC dialect's point lists hold piecewise-linear terms only: writing a
smooth shape in it is refused (the named dialect writes it).

Semantics kept: FCL has no input clamping (``out_of_range: extend``); ``DEFAULT := v`` applies
where no rule fires (``NC``, keep the previous value, is refused); ``ACCU`` may sit in the
``DEFUZZIFY`` block (fuzzylite) or in the ``RULEBLOCK`` (IEC); ``METHOD : COGS`` and ``COGSS``
are Sugeno weighted average and weighted sum; an ``AND`` or ``OR`` not declared is the De
Morgan partner of the one declared (``MIN``/``MAX``, ``PROD``/``ASUM``). Keywords are
case-insensitive; comments are ``(* ... *)``, ``/* ... */`` and ``//``. Statements end with
``;`` or at the end of the line.

Ranges: IEC 61131-7 gives a ``FUZZIFY`` block no ``RANGE`` (and makes it optional in
``DEFUZZIFY``); jFuzzyLogic also accepts ``RANGE := (low .. high)`` after the declaration in
``VAR_INPUT``/``VAR_OUTPUT``. A variable without one gets the span of its terms (see
:func:`term_span`), as jFuzzyLogic derives its universe; :func:`loads_with_notes` says which.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path as FsPath
from typing import Literal

from fuzzkit.errors import Problem
from fuzzkit.formats.fll import named_term, term_body
from fuzzkit.formats.foreign_common import (
    SUGENO_DEFUZZIFIERS,
    Collector,
    ExportError,
    ForeignFormat,
    finish,
    fmt,
    is_sugeno,
    parse_number,
    points_to_term,
    read_named,
    read_text,
    term_to_points,
)
from fuzzkit.formats.rule_text import parse_rule, rule_text
from fuzzkit.fuzzy import shapes
from fuzzkit.fuzzy.model import Operators, Rule, RuleBase, Term, Variable

SUFFIX = ".fcl"
Dialect = Literal["iec", "named"]

_AND = {"MIN": "min", "PROD": "product"}
_OR = {"MAX": "max", "ASUM": "probabilistic_sum", "PROBOR": "probabilistic_sum"}
_ACT = {"MIN": "min", "PROD": "product"}
_ACCU = {
    "MAX": "max",
    "BSUM": "bounded_sum",
    "ASUM": "probabilistic_sum",
    "PROBOR": "probabilistic_sum",
}
_METHOD = {
    "COG": "centroid",
    "COA": "bisector",
    "MM": "mean_of_maximum",
    "LM": "smallest_of_maximum",
    "RM": "largest_of_maximum",
    "COGS": "weighted_average",
    "COGSS": "weighted_sum",
}
#: jFuzzyLogic's shapes that are not fuzzkit's (those that are, TRIAN, TRAPE, GAUSS, GAUSS2,
#: GBELL and SIGM, are the shape registry's ``fcl`` spellings).
_JFL_REFUSED = {
    "DSIGM": "DSIGM is jFuzzyLogic's max(s1 - s2, 0), not MATLAB's |s1 - s2| "
    "(sigmoid_difference; write SigmoidDifference): refused, not approximated",
}
#: De Morgan partners: the OR an AND implies when only the AND is declared, and back.
_DE_MORGAN = {"min": "max", "product": "probabilistic_sum"}
_PAIR = re.compile(r"\(\s*([^,()]+?)\s*,\s*([^,()]+?)\s*\)")
# an unterminated comment runs to the end of the file (one match, so scanning stays linear)
_COMMENTS = re.compile(r"\(\*.*?(?:\*\)|\Z)|/\*.*?(?:\*/|\Z)|//[^\n]*", re.DOTALL)


@dataclass
class _Stmt:
    text: str
    line: int
    col: int

    @property
    def head(self) -> str:
        return self.text.split(None, 1)[0].upper() if self.text else ""

    def rest(self) -> tuple[str, int]:
        """The text after the first word, and its column."""
        parts = self.text.split(None, 1)
        if len(parts) < 2:
            return "", self.col + len(self.text)
        return parts[1], self.col + self.text.index(parts[1], len(parts[0]))


def _statements(text: str) -> list[_Stmt]:
    # blank out comments, keeping every character's line and column
    clean = _COMMENTS.sub(lambda m: re.sub(r"[^\n]", " ", m.group()), text)
    out: list[_Stmt] = []
    for n, line in enumerate(clean.split("\n"), start=1):
        pos = 0
        for piece in line.split(";"):
            stripped = piece.strip()
            if stripped:
                out.append(_Stmt(stripped, n, pos + piece.index(stripped) + 1))
            pos += len(piece) + 1
    # a block keyword may share its statement with what follows it ("VAR_INPUT x : REAL")
    split: list[_Stmt] = []
    for s in out:
        while s.head in _OPENERS | _CLOSERS and s.text.split(None, 1)[1:]:
            word = s.text.split(None, 1)[0]
            if s.head in ("FUZZIFY", "DEFUZZIFY", "RULEBLOCK", "FUNCTION_BLOCK"):
                parts = s.text.split(None, 2)
                if len(parts) < 3:
                    break
                split.append(_Stmt(f"{parts[0]} {parts[1]}", s.line, s.col))
                rest = parts[2]
            else:
                split.append(_Stmt(word, s.line, s.col))
                rest = s.text.split(None, 1)[1]
            s = _Stmt(rest, s.line, s.col + s.text.index(rest, len(word)))
        split.append(s)
    return split


_OPENERS = frozenset(
    {"FUNCTION_BLOCK", "VAR_INPUT", "VAR_OUTPUT", "FUZZIFY", "DEFUZZIFY", "RULEBLOCK"}
)
_CLOSERS = frozenset(
    {"END_VAR", "END_FUZZIFY", "END_DEFUZZIFY", "END_RULEBLOCK", "END_FUNCTION_BLOCK"}
)


@dataclass
class _Var:
    name: str
    kind: str
    line: int
    col: int
    low: float | None = None
    high: float | None = None
    #: (statement, term name, definition, column of the definition)
    terms: list[tuple[_Stmt, str, str, int]] = field(default_factory=list)
    default: float | None = None
    #: line and column of its FUZZIFY/DEFUZZIFY block, where a derived range is located
    block: tuple[int, int] | None = None


def _assign(s: _Stmt, found: Collector, sep: str) -> tuple[str, int] | None:
    """The right side of ``KEY sep value`` and its column."""
    rest, col = s.rest()
    if not rest.startswith(sep):
        found.add(s.line, col, f"{s.head}: expected {sep!r}, got {rest!r}")
        return None
    value = rest[len(sep) :]
    return value.strip(), col + len(sep) + (len(value) - len(value.lstrip()))


def _range(s: _Stmt, var: _Var, found: Collector) -> None:
    """``RANGE := (low .. high)`` of ``var``."""
    got = _assign(s, found, ":=")
    m = re.fullmatch(r"\(\s*(\S+)\s*\.\.\s*(\S+)\s*\)", got[0]) if got else None
    lo = parse_number(m.group(1)) if m else None
    hi = parse_number(m.group(2)) if m else None
    if got is not None and (lo is None or hi is None):
        found.add(s.line, got[1], f"RANGE: expected (low .. high), got {got[0]!r}")
    elif lo is not None and hi is not None and got is not None:
        var.low, var.high = lo, hi
        found.mark((var.kind + "s", var.name, "range"), s.line, got[1])


def term_span(body: str, term: Term) -> tuple[float, float] | None:
    """Where a term lies on its axis, for a variable without ``RANGE``; None if unknown.

    A point list spans its first to its last point (held constant beyond them, so these are
    where its shape is); a named shape spans what its shape registry record's ``span`` says
    (:attr:`fuzzkit.fuzzy.shapes.Shape.span`): its parameters when they are all positions,
    jFuzzyLogic's estimates of where a smooth shape becomes negligible, or nothing.
    """
    if body.startswith("("):
        xs = [parse_number(x) for x, _ in _PAIR.findall(body)]
        pts = [x for x in xs if x is not None]
        return (min(pts), max(pts)) if pts else None
    span = shapes.shape(term.shape).span
    return None if span is None else span(term.params)


def _word(s: _Stmt, table: dict[str, str], found: Collector) -> str | None:
    got = _assign(s, found, ":")
    if got is None:
        return None
    word, col = got
    if word.upper() not in table:
        found.add(
            s.line,
            col,
            f"{s.head} : {word} cannot be expressed in fuzzkit; expected one of {', '.join(table)}",
        )
        return None
    return table[word.upper()]


def _term_def(body: str, name: str, output: bool, sugeno: bool, n_inputs: int) -> Term | str:
    if body.startswith("("):
        pairs = _PAIR.findall(body)
        if _PAIR.sub("", body).strip() or not pairs:
            return f"expected a point list like (0, 0) (5, 1) (10, 0), got {body!r}"
        points = []
        for x, y in pairs:
            px, py = parse_number(x), parse_number(y)
            if px is None or py is None:
                return f"point ({x}, {y}): expected numbers"
            points.append((px, py))
        if output and sugeno:
            return "a Sugeno output takes Constant or Linear terms, not a point list"
        return points_to_term(name, points)
    words = body.split()
    if not words:  # a truncated file: "TERM x :=" and nothing after it
        return "expected a term after ':=' (a point list, a number or a shape), got nothing"
    value = parse_number(body)
    if value is not None:  # IEC singleton
        if output:
            return (
                Term(name, "constant", (value,))
                if sugeno
                else ("a singleton output term belongs to a Sugeno system (METHOD : COGS)")
            )
        return Term(name, "singleton", (value,))
    cls, args_text = words[0], words[1:]
    args = [parse_number(a) for a in args_text]
    if any(a is None for a in args):
        return f"{cls}: expected numbers after it, got {' '.join(args_text)!r}"
    nums = [a for a in args if a is not None]
    upper = cls.upper()
    if upper in _JFL_REFUSED:
        return _JFL_REFUSED[upper]
    jfl = {k.upper(): k for k in shapes.spellings("fcl")}
    if upper in jfl:  # jFuzzyLogic's names, case-insensitive as its keywords
        spelling = shapes.spellings("fcl")[jfl[upper]][0][1]
        if len(nums) != spelling.arity:
            return f"{cls} needs {spelling.arity} parameters, got {len(nums)}"
        if output and sugeno:
            return f"{cls}: a Sugeno output takes Constant or Linear terms"
        return read_named("fcl", name, jfl[upper], nums)
    return named_term(name, cls, nums, output and sugeno, n_inputs)


def loads(text: str, source: str = "<string>") -> RuleBase:
    """Parse the text of a file of this format (see :func:`loads_with_warnings`)."""
    return loads_with_warnings(text, source)[0]


def loads_with_warnings(text: str, source: str = "<string>") -> tuple[RuleBase, list[Problem]]:
    """Parse FCL text (either dialect) into a rule base; ``source`` names it in messages.

    Returns the rule base and the warnings (coverage gaps, located; see
    :func:`fuzzkit.formats.foreign_common.finish`).

    Raises
    ------
    RuleBaseError
        Every problem as ``source:line:col: message``.
    """
    rb, warnings, _ = loads_with_notes(text, source)
    return rb, warnings


def loads_with_notes(
    text: str, source: str = "<string>"
) -> tuple[RuleBase, list[Problem], dict[str, str]]:
    """:func:`loads_with_warnings`, also saying how each range without ``RANGE`` was derived.

    The third item maps the name of every variable whose file gives no ``RANGE`` to a note
    (``fuzzkit import`` writes it as a comment on the YAML range).
    """
    found = Collector(source)
    stmts = _statements(text)
    if not stmts or stmts[0].head != "FUNCTION_BLOCK":
        found.add(
            stmts[0].line if stmts else 1,
            stmts[0].col if stmts else 1,
            "expected FUNCTION_BLOCK first (is this an .fcl file?)",
        )
        found.fail()
    fb_name, fb_col = stmts[0].rest()
    name = fb_name.strip() or "imported"
    found.mark(("name",), stmts[0].line, fb_col)
    variables: dict[str, _Var] = {}
    order: dict[str, list[str]] = {"input": [], "output": []}
    block: str = "FUNCTION_BLOCK"
    current: _Var | None = None
    ops: dict[str, tuple[str, _Stmt]] = {}
    methods: list[tuple[str, _Stmt]] = []
    accus: list[tuple[str, _Stmt]] = []
    rule_stmts: list[_Stmt] = []
    last_declared: _Var | None = None
    ended = False
    for s in stmts[1:]:
        head = s.head
        if ended:
            found.add(s.line, s.col, f"unexpected {s.text!r} after END_FUNCTION_BLOCK")
            break
        if head in ("VAR_INPUT", "VAR_OUTPUT"):
            block, last_declared = head, None
            continue
        if head in _CLOSERS:
            if head == "END_FUNCTION_BLOCK":
                ended = True
            block, current = "FUNCTION_BLOCK", None
            continue
        if block in ("VAR_INPUT", "VAR_OUTPUT"):
            if head == "RANGE":  # jFuzzyLogic: `x : REAL; RANGE := (0 .. 10);`
                if last_declared is None:
                    found.add(s.line, s.col, "RANGE before any variable declaration")
                else:
                    _range(s, last_declared, found)
                continue
            vname, colon, vtype = s.text.partition(":")
            kind = "input" if block == "VAR_INPUT" else "output"
            if not colon or vtype.strip().upper() != "REAL":
                found.add(s.line, s.col, f"expected 'name : REAL;', got {s.text!r}")
                continue
            vname = vname.strip()
            if vname in variables:
                found.add(s.line, s.col, f"variable {vname!r} declared twice")
                continue
            variables[vname] = last_declared = _Var(vname, kind, s.line, s.col)
            order[kind].append(vname)
            continue
        if head in ("FUZZIFY", "DEFUZZIFY"):
            vname, vcol = s.rest()
            current = variables.get(vname)
            want = "input" if head == "FUZZIFY" else "output"
            if current is None or current.kind != want:
                found.add(
                    s.line,
                    vcol,
                    f"{head} {vname}: no {want} {vname!r} declared in VAR_{want.upper()}",
                )
                current = None
            elif current.block is None:
                current.block = (s.line, s.col)
            block = head
            continue
        if head == "RULEBLOCK":
            block = head
            found.mark(("rules",), s.line, s.col)  # where a rule-coverage gap is reported
            continue
        if block in ("FUZZIFY", "DEFUZZIFY"):
            if current is None:
                continue  # the block's header was already reported
            if head == "RANGE":
                _range(s, current, found)
            elif head == "TERM":
                rest, rcol = s.rest()
                tname, eq, body = rest.partition(":=")
                if not eq:
                    found.add(s.line, rcol, f"TERM: expected 'name := definition', got {rest!r}")
                    continue
                bcol = rcol + len(tname) + 2 + (len(body) - len(body.lstrip()))
                current.terms.append((s, tname.strip(), body.strip(), bcol))
            elif head == "METHOD" and block == "DEFUZZIFY":
                method = _word(s, _METHOD, found)
                if method is not None:
                    methods.append((method, s))
            elif head == "ACCU" and block == "DEFUZZIFY":
                accu = _word(s, _ACCU, found)
                if accu is not None:
                    accus.append((accu, s))
            elif head == "DEFAULT" and block == "DEFUZZIFY":
                got = _assign(s, found, ":=")
                if got is None:
                    continue
                value_text, _, nc = got[0].partition("|")
                if nc.strip() or value_text.strip().upper() == "NC":
                    found.add(
                        s.line,
                        got[1],
                        "DEFAULT ... | NC (keep the previous value when no "
                        "rule fires) cannot be expressed in fuzzkit",
                    )
                    continue
                value = parse_number(value_text.strip())
                if value is None:
                    found.add(
                        s.line,
                        got[1],
                        f"DEFAULT: expected a number or nan, got {value_text.strip()!r}",
                    )
                elif not math.isnan(value):
                    current.default = value
                found.mark(("outputs", current.name, "default"), s.line, got[1])
            elif head == "LOCK" and block == "DEFUZZIFY":
                got = _assign(s, found, ":")
                if got is not None and got[0].upper() != "RANGE":
                    found.add(s.line, got[1], f"LOCK : {got[0]} cannot be expressed in fuzzkit")
            else:
                found.add(s.line, s.col, f"unexpected {s.text!r} in {block} {current.name}")
            continue
        if block == "RULEBLOCK":
            if head in ("AND", "OR", "ACT"):
                table = {"AND": _AND, "OR": _OR, "ACT": _ACT}[head]
                op = _word(s, table, found)
                if op is not None:
                    if head in ops and ops[head][0] != op:
                        found.add(s.line, s.col, f"{head} given twice with different values")
                    ops[head] = (op, s)
            elif head == "ACCU":
                accu = _word(s, _ACCU, found)
                if accu is not None:
                    accus.append((accu, s))
            elif head == "RULE":
                rule_stmts.append(s)
            else:
                found.add(
                    s.line,
                    s.col,
                    f"unexpected {s.text!r} in RULEBLOCK (expected AND, "
                    "OR, ACT, ACCU or RULE n : IF ... THEN ...)",
                )
            continue
        found.add(
            s.line,
            s.col,
            f"unexpected {s.text!r} (expected VAR_INPUT, VAR_OUTPUT, "
            "FUZZIFY, DEFUZZIFY or RULEBLOCK)",
        )
    if not ended:
        found.add(len(text.splitlines()) or 1, 1, "missing END_FUNCTION_BLOCK (truncated file?)")
    defuzz = methods[0][0] if methods else None
    for method, s in methods[1:]:
        if method != defuzz:
            found.add(
                s.line,
                s.col,
                f"METHOD differs between outputs (first was {defuzz}); "
                "fuzzkit uses one defuzzifier",
            )
    if methods:
        found.mark(("defuzzifier",), methods[0][1].line, methods[0][1].col)
    sugeno = defuzz in SUGENO_DEFUZZIFIERS
    if not methods and order["output"]:
        found.add(variables[order["output"][0]].line, 1, "no METHOD : ... for the outputs")
    agg = accus[0][0] if accus else None
    for accu, s in accus[1:]:
        if accu != agg:
            found.add(s.line, s.col, f"ACCU differs (first was {agg}); fuzzkit uses one")
    if accus:
        found.mark(("operators", "aggregation"), accus[0][1].line, accus[0][1].col)
    if sugeno and accus:
        found.add(
            accus[0][1].line,
            accus[0][1].col,
            "ACCU in a Sugeno system (COGS/COGSS): "
            "fuzzkit weights every rule separately; remove it",
        )
    built: dict[str, list[Variable]] = {"input": [], "output": []}
    notes: dict[str, str] = {}
    n_inputs = len(order["input"])
    for kind in ("input", "output"):
        for vname in order[kind]:
            v = variables[vname]
            base = (kind + "s", vname)
            found.mark(base, v.line, v.col)
            terms: list[Term] = []
            spans: list[tuple[_Stmt, Term, tuple[float, float] | None]] = []
            seen: set[str] = set()
            for s, tname, body, bcol in v.terms:
                term = _term_def(body, tname, kind == "output", sugeno, n_inputs)
                if isinstance(term, str):
                    found.add(s.line, bcol, f"TERM {tname}: {term}")
                    continue
                spans.append((s, term, term_span(body, term)))
                if tname in seen:
                    found.add(
                        s.line,
                        s.col,
                        f"term name {tname!r} appears twice in {kind} "
                        f"{vname!r}; a rule naming it would be ambiguous",
                    )
                    continue
                seen.add(tname)
                found.mark((*base, "terms", tname), s.line, bcol)
                terms.append(term)
            if v.low is None or v.high is None:
                derived = _derived_range(v, spans, len(spans) < len(v.terms), found)
                # reported when None; a stand-in keeps the rules' references to it quiet
                v.low, v.high = derived or (0.0, 1.0)
                notes[vname] = f"derived: the span of its terms (no RANGE in {FsPath(source).name})"
            built[kind].append(Variable(vname, v.low, v.high, tuple(terms), v.default))
    by_in = {v.name: v for v in built["input"]}
    by_out = {v.name: v for v in built["output"]}
    rules: list[Rule] = []
    for s in rule_stmts:
        rest, rcol = s.rest()
        label, colon, body = rest.partition(":")
        if not colon:
            found.add(s.line, rcol, f"expected 'RULE n : IF ... THEN ...', got {s.text!r}")
            continue
        bcol = rcol + len(label) + 1 + (len(body) - len(body.lstrip()))
        rule = parse_rule(body.strip(), s.line, bcol, by_in, by_out, found)
        if rule is not None:
            found.mark(("rules", len(rules)), s.line, s.col)
            rules.append(rule)
    if not rule_stmts and ended:
        found.add(1, 1, "no RULEBLOCK with rules")
    for head, (_, s) in ops.items():
        key = {"AND": "and", "OR": "or", "ACT": "implication"}[head]
        found.mark(("operators", key), s.line, s.col)
    found.raise_if_any()
    rb = RuleBase(
        name=name,
        inputs=tuple(built["input"]),
        outputs=tuple(built["output"]),
        rules=tuple(rules),
        operators=Operators(*_and_or(ops), ops["ACT"][0] if "ACT" in ops else "min", agg or "max"),
        defuzzifier=defuzz or "centroid",
        out_of_range="extend",
    )
    return (*finish(rb, found, text), notes)


def _and_or(ops: dict[str, tuple[str, _Stmt]]) -> tuple[str, str]:
    """AND and OR; one not declared is the De Morgan partner of the other (IEC 61131-7)."""
    and_ = ops["AND"][0] if "AND" in ops else None
    or_ = ops["OR"][0] if "OR" in ops else None
    if and_ is None:
        and_ = next((a for a, o in _DE_MORGAN.items() if o == or_), "min")
    return and_, or_ if or_ is not None else _DE_MORGAN[and_]


def _derived_range(
    v: _Var,
    spans: list[tuple[_Stmt, Term, tuple[float, float] | None]],
    broken: bool,
    found: Collector,
) -> tuple[float, float] | None:
    """The span of a variable's terms, for a variable without RANGE (or why not, reported).

    ``broken``: a term did not parse (reported already), so the span would be a guess.
    """
    line, col = v.block or (v.line, v.col)
    what = f"{v.kind} {v.name!r} has no RANGE := (low .. high)"
    if not spans and not broken:
        found.add(line, col, f"{what} and no terms to derive it from")
        return None
    known: list[tuple[float, float]] = []
    for s, term, span in spans:
        if span is None:
            found.add(
                s.line,
                s.col,
                f"{what}, and TERM {term.name} ({term.shape}) has no place on the axis to "
                "derive it from: add a RANGE",
            )
        else:
            known.append(span)
    if broken or len(known) < len(spans):
        return None
    low, high = min(lo for lo, _ in known), max(hi for _, hi in known)
    if not low < high:
        found.add(
            line,
            col,
            f"{what}, and its terms all sit at {fmt(low)}: add a RANGE to give it a width",
        )
        return None
    found.mark((v.kind + "s", v.name, "range"), line, col)
    return low, high


def load(path: str | FsPath) -> RuleBase:
    """Read an ``.fcl`` file (see :func:`loads`)."""
    return loads(read_text(path, "an .fcl file"), str(path))


def load_with_warnings(path: str | FsPath) -> tuple[RuleBase, list[Problem]]:
    """:func:`load`, also returning the warnings (coverage gaps), located."""
    return loads_with_warnings(read_text(path, "an .fcl file"), str(path))


def load_with_notes(path: str | FsPath) -> tuple[RuleBase, list[Problem], dict[str, str]]:
    """:func:`load_with_warnings`, also the notes on derived ranges (:func:`loads_with_notes`)."""
    return loads_with_notes(read_text(path, "an .fcl file"), str(path))


# ---------------------------------------------------------------------------- export


def _term_line(term: Term, dialect: Dialect) -> str | None:
    if dialect == "iec":
        if term.shape in ("constant", "singleton"):
            return fmt(term.params[0])
        points = term_to_points(term)
        if points is None:
            return None
        return " ".join(f"({fmt(x)}, {fmt(y)})" for x, y in points)
    if term.shape == "singleton":
        return fmt(term.params[0])
    return term_body(term)


def refusals(rb: RuleBase, dialect: Dialect = "named") -> list[str]:
    """What in ``rb`` this FCL dialect cannot express (export is refused)."""
    out: list[str] = []
    sugeno = is_sugeno(rb)
    if (rb.defuzzifier in SUGENO_DEFUZZIFIERS) != sugeno:
        out.append(
            f"defuzzifier {rb.defuzzifier!r} with {'Sugeno' if sugeno else 'Mamdani'} "
            "terms (COGS/COGSS are Sugeno weighted average and sum)"
        )
    for var in rb.inputs + rb.outputs:
        for term in var.terms:
            if _term_line(term, dialect) is None:
                extra = (
                    " (IEC point lists draw piecewise-linear terms only; use the named dialect)"
                    if dialect == "iec"
                    else ""
                )
                out.append(f"term {var.name}.{term.name}: shape {term.shape!r}{extra}")
    return out


def losses(rb: RuleBase) -> list[str]:
    """What an FCL file would change in ``rb`` (export needs ``allow_loss=True``)."""
    if rb.out_of_range == "clamp":
        return [
            "out_of_range: clamp (FCL has no input clamping, so results differ outside the "
            "input ranges)"
        ]
    return []


def dumps(rb: RuleBase, *, dialect: Dialect = "named", allow_loss: bool = False) -> str:
    """The FCL text of ``rb`` in ``dialect`` (``named`` shapes or ``iec`` point lists).

    ``loads(dumps(rb))`` equals ``rb`` up to its description. The named dialect is what
    fuzzylite reads (``ACCU`` in ``DEFUZZIFY``, lower-case rule keywords); the IEC dialect
    follows IEC 61131-7 (``ACCU`` in the ``RULEBLOCK``, upper-case keywords).

    Raises
    ------
    ExportError
        See :func:`refusals` and :func:`losses`.
    """
    problems = refusals(rb, dialect)
    if problems:
        raise ExportError("fcl", rb.name, problems)
    if not allow_loss and losses(rb):
        raise ExportError(
            "fcl",
            rb.name,
            losses(rb),
            "pass allow_loss=True (--allow-loss) to export anyway, with FCL's meaning for these",
        )
    sugeno = is_sugeno(rb)
    rev = {v: k for k, v in _METHOD.items()}
    accu = next(k for k, v in _ACCU.items() if v == rb.operators.aggregation)
    lines = [f"FUNCTION_BLOCK {rb.name}", ""]
    for title, group in (("VAR_INPUT", rb.inputs), ("VAR_OUTPUT", rb.outputs)):
        lines += [title, *(f"  {v.name} : REAL;" for v in group), "END_VAR", ""]
    for var in rb.inputs:
        lines += [f"FUZZIFY {var.name}", f"  RANGE := ({fmt(var.low)} .. {fmt(var.high)});"]
        lines += [f"  TERM {t.name} := {_term_line(t, dialect)};" for t in var.terms]
        lines += ["END_FUZZIFY", ""]
    for var in rb.outputs:
        lines += [f"DEFUZZIFY {var.name}", f"  RANGE := ({fmt(var.low)} .. {fmt(var.high)});"]
        lines += [f"  TERM {t.name} := {_term_line(t, dialect)};" for t in var.terms]
        lines.append(f"  METHOD : {rev[rb.defuzzifier]};")
        if dialect == "named" and not sugeno:
            lines.append(f"  ACCU : {accu};")
        lines += [
            f"  DEFAULT := {'nan' if var.default is None else fmt(var.default)};",
            "END_DEFUZZIFY",
            "",
        ]
    ops = rb.operators
    lines += [
        "RULEBLOCK rules",
        f"  AND : {next(k for k, v in _AND.items() if v == ops.and_)};",
        f"  OR : {next(k for k, v in _OR.items() if v == ops.or_)};",
        f"  ACT : {next(k for k, v in _ACT.items() if v == ops.implication)};",
    ]
    if dialect == "iec" and not sugeno:
        lines.append(f"  ACCU : {accu};")
    for k, rule in enumerate(rb.rules, start=1):
        lines.append(f"  RULE {k} : {rule_text(rule, upper=dialect == 'iec')};")
    lines += ["END_RULEBLOCK", "", "END_FUNCTION_BLOCK"]
    return "\n".join(lines) + "\n"


def _write(rb: RuleBase, allow_loss: bool, dialect: str) -> str:
    if dialect not in FORMAT.dialects:
        raise ValueError(f"unknown FCL dialect {dialect!r}; expected named or iec")
    return dumps(rb, dialect="iec" if dialect == "iec" else "named", allow_loss=allow_loss)


#: The format as :data:`fuzzkit.formats.registry.FORMATS` lists it.
FORMAT = ForeignFormat(
    name="fcl",
    suffix=SUFFIX,
    label="IEC 61131-7 .fcl",
    first_word="FUNCTION_BLOCK",
    read=load_with_warnings,
    write=_write,
    losses=losses,
    meaning="FCL's",
    dialects=("named", "iec"),
)
