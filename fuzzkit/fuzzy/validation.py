"""Semantic checks of a rule base, shared by the YAML loader and every engine.

:func:`check` gathers every problem of a :class:`~fuzzkit.fuzzy.model.RuleBase` as
``(path, message)`` pairs, where ``path`` is a logical path into the rule-base document:

* ``("name",)``, ``("defuzzifier",)``, ``("out_of_range",)``, ``("operators", "and")``;
* ``("inputs", "e")``, ``("inputs", "e", "range")``, ``("inputs", "e", "terms")`` (coverage),
  ``("inputs", "e", "terms", "NL")``, ``("inputs", "e", "terms", "NL", "points")`` for the
  piecewise-linear shapes and ``(..., "NL", "sigma")`` (the parameter's name) for the others;
* ``("outputs", "du", "default")``, ``("outputs", "du", "terms", "Z", "coefficients")`` for a
  linear Sugeno term's coefficients, ``("coverage",)``,
  ``("inputs", "e", "units")``;
* ``("rules",)``, ``("rules", "table", "rows")``, and for rule ``k`` (its index in
  ``RuleBase.rules``): ``("rules", k, "weight")``, ``("rules", k, "then", j)`` for its ``j``-th
  consequent and ``("rules", k, "if", i, j, ...)`` for the sub-expression reached by taking
  operand ``i`` of the antecedent, then operand ``j`` of that, and so on; a problem with the
  label of a proposition or consequent (rather than its variable) adds ``"label"``.

The YAML loader maps these paths to ``file:line:col``; :func:`ensure_valid` (what engines call)
raises one :class:`~fuzzkit.errors.RuleBaseError` naming every problem with its path.

Coverage gaps (part of an input's range where no term is above zero) are the one kind of
problem that can be a warning: :func:`diagnose` returns errors and warnings separately, and
``check(rb, allow_gaps=True)`` returns only the errors. By default ``RuleBase.coverage`` decides
(``strict``: gaps are errors; ``allow_gaps``: warnings). Importers of foreign formats build
models with ``coverage="allow_gaps"``.
"""

from __future__ import annotations

import keyword
import math
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import TypeAlias

from fuzzkit.errors import Location, Problem, RuleBaseError, did_you_mean
from fuzzkit.fuzzy import membership_bounds, resolution, rule_coverage, term_placement
from fuzzkit.fuzzy.model import (
    AGGREGATIONS,
    AND_OPERATORS,
    COVERAGE_POLICIES,
    DEFUZZIFIERS,
    IMPLICATIONS,
    OR_OPERATORS,
    OUT_OF_RANGE_POLICIES,
    PIECEWISE_LINEAR_SHAPES,
    SHAPE_PARAMS,
    SUGENO_DEFUZZIFIERS,
    Compound,
    Expression,
    RuleBase,
    Term,
    Variable,
)
from fuzzkit.fuzzy.shapes import shape as shape_record
from fuzzkit.fuzzy.type2_model import Type2RuleBase
from fuzzkit.fuzzy.type2_validation import footprint_problems

PathPart: TypeAlias = str | int
Path: TypeAlias = tuple[PathPart, ...]
Issue: TypeAlias = tuple[Path, str]

IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")

#: C keywords (C99, C11 and C23, including the C23 spellings of the old macros like ``bool``),
#: plus names every generated C file sees through the standard headers it includes.
C_KEYWORDS = frozenset(
    """
    auto break case char const continue default do double else enum extern float for goto if
    inline int long register restrict return short signed sizeof static struct switch typedef
    union unsigned void volatile while
    _Alignas _Alignof _Atomic _Bool _Complex _Generic _Imaginary _Noreturn _Static_assert
    _Thread_local _BitInt _Decimal32 _Decimal64 _Decimal128
    alignas alignof bool constexpr false nullptr static_assert thread_local true typeof
    typeof_unqual
    NULL NAN INFINITY EOF
    int8_t int16_t int32_t int64_t uint8_t uint16_t uint32_t uint64_t
    """.split()  # noqa: SIM905 (a word list reads better than 60 quoted strings)
)

#: Units are a label (``N``, ``mm/s``, ``degC``), not prose; longer ones would crowd every axis.
MAX_UNITS_CHARS = 24

#: Python keywords, soft keywords (``match``, ``case``, ``type``, ``_``) included.
PYTHON_KEYWORDS = frozenset(keyword.kwlist) | frozenset(keyword.softkwlist)


#: Names (rule base, variables, terms) are at most this long: C99 guarantees 63 significant
#: characters in an identifier, and a generated symbol adds the rule base's name to it.
MAX_NAME_CHARS = 64
#: Conditions nest at most this many and/or levels; every reader and writer obeys it.
MAX_CONDITION_DEPTH = 32


def name_problem(name: str) -> str | None:
    """Why ``name`` cannot name a rule base, variable or term, or ``None`` when it can.

    Keywords of the target languages are fine (``in``, ``class``): names are the user's, and
    code generation mangles the one that becomes an identifier (``fuzzkit.codegen.names``).
    """
    if len(name) > MAX_NAME_CHARS:
        return (
            f"name {name[:20]!r}... is {len(name)} characters long; names are limited to "
            f"{MAX_NAME_CHARS} characters"
        )
    if not IDENTIFIER.match(name):
        return f"expected an identifier matching [A-Za-z_][A-Za-z0-9_]*, got {name!r}"
    return None


def identifier_problem(name: str) -> str | None:
    """Why ``name`` cannot become a C and Python identifier as it is, or ``None`` when it can."""
    why = name_problem(name)
    if why is not None:
        return why
    if name in C_KEYWORDS and name in PYTHON_KEYWORDS:
        return f"{name!r} is a C and Python keyword; choose another name"
    if name in C_KEYWORDS:
        return f"{name!r} is a C keyword or reserved name; choose another name"
    if name in PYTHON_KEYWORDS:
        return f"{name!r} is a Python keyword; choose another name"
    # C reserves these for the implementation; a generated symbol could clash with libc.
    if name.startswith("__") or (len(name) > 1 and name[0] == "_" and name[1].isupper()):
        return f"{name!r} is reserved in C (leading '__' or '_' + capital); choose another name"
    return None


def units_problem(units: str) -> str | None:
    """Why ``units`` cannot label a variable (``None`` if it can): one short printable line."""
    if not units.strip():
        return "expected a unit such as 'N' or 'mm', got an empty string"
    if units != units.strip():
        return f"expected no leading or trailing spaces, got {units!r}"
    if len(units) > MAX_UNITS_CHARS:
        return f"expected at most {MAX_UNITS_CHARS} characters, got {len(units)}"
    if not units.isprintable():
        return f"expected printable characters on one line, got {units!r}"
    return None


def _fmt(x: float) -> str:
    return repr(float(x)) if not float(x).is_integer() else str(float(x))


def _fmt_list(values: Sequence[float]) -> str:
    return "[" + ", ".join(_fmt(v) for v in values) + "]"


# ---------------------------------------------------------------------------- terms


def term_param_path(term: Term) -> PathPart:
    """The document key holding a term's parameters: ``points`` or the first parameter name."""
    if term.shape in PIECEWISE_LINEAR_SHAPES:
        return "points"
    return SHAPE_PARAMS[term.shape][0] if term.shape in SHAPE_PARAMS else "shape"


def _check_term(term: Term, base: Path, n_inputs: int = 0) -> list[Issue]:
    shape, p = term.shape, term.params
    if shape not in SHAPE_PARAMS:
        return [
            (
                (*base, "shape"),
                f"unknown shape {shape!r}{did_you_mean(shape, SHAPE_PARAMS)}; "
                f"expected one of {', '.join(SHAPE_PARAMS)}",
            )
        ]
    if shape == "linear":
        return _check_linear(term, base, n_inputs)
    names = SHAPE_PARAMS[shape]
    pwl = shape in PIECEWISE_LINEAR_SHAPES
    where: Path = (*base, "points") if pwl else base
    if len(p) != len(names):
        what = "points" if pwl else "parameters (" + ", ".join(names) + ")"
        return [(where, f"{shape} needs {len(names)} {what}, got {len(p)}")]
    bad = [n for n, v in zip(names, p, strict=True) if not math.isfinite(v)]
    if bad:
        if pwl:
            return [(where, f"{shape} points must be finite numbers, got {_fmt_list(p)}")]
        return [((*base, n), f"{n} must be a finite number, got {p[names.index(n)]}") for n in bad]
    return [
        ((*base, key) if key != "points" else where, message)
        for key, message in shape_record(shape).check(p)
    ]


def _check_linear(term: Term, base: Path, n_inputs: int) -> list[Issue]:
    p = term.params
    if len(p) != n_inputs + 1:
        return [
            (
                (*base, "coefficients"),
                f"linear term needs {n_inputs} coefficient(s) (one per input) and a constant, "
                f"got {len(p)} numbers in all",
            )
        ]
    if not all(math.isfinite(v) for v in p):
        return [((*base, "coefficients"), f"linear coefficients must be finite, got {list(p)}")]
    return []


def _term_is_valid(term: Term) -> bool:
    return not _check_term(term, ())


# ---------------------------------------------------------------------------- coverage


def uncovered(var: Variable) -> list[tuple[float, float]]:
    """The closed intervals of ``[low, high]`` where no term of ``var`` has a computed
    membership > 0 (a Gaussian's tail that underflows to 0 is not covered).

    Decided by sound bounds of the computed membership (:mod:`fuzzkit.fuzzy.membership_bounds`),
    down to single floats where a term's membership reaches 0. A gap of a single point is
    reported as ``(x, x)``.
    """
    return membership_bounds.positive_parts(var)


# ---------------------------------------------------------------------------- variables


def _check_variable(var: Variable, kind: str, base: Path, rb: RuleBase) -> list[Issue]:
    out: list[Issue] = []
    why = name_problem(var.name)
    if why:
        out.append((base, f"{kind} name: {why}"))
    range_ok = math.isfinite(var.low) and math.isfinite(var.high) and var.low < var.high
    if not range_ok:
        out.append(
            (
                (*base, "range"),
                "range must be [low, high] with finite low < high, "
                f"got [{_fmt(var.low)}, {_fmt(var.high)}]",
            )
        )
    elif (why := resolution.range_problem(var)) is not None:
        out.append(((*base, "range"), why))
        range_ok = False
    if not var.terms and not (kind == "input" and _used_in_linear(rb, var.name)):
        hint = (
            " (an input may have none only when a linear output term uses it)"
            if kind == "input"
            else ""
        )
        out.append(((*base, "terms"), f"{kind} {var.name!r} has no terms{hint}"))
    seen: set[str] = set()
    for term in var.terms:
        tpath: Path = (*base, "terms", term.name)
        if term.name in seen:
            out.append((tpath, f"duplicate term {term.name!r} in {kind} {var.name!r}"))
        seen.add(term.name)
        why = name_problem(term.name)
        if why:
            out.append((tpath, f"term name: {why}"))
        if kind == "input" and term.is_sugeno:
            out.append(
                (
                    (*tpath, "shape"),
                    f"{term.shape} is a Sugeno output term; input terms must be membership "
                    "functions (triangle, gaussian, ...)",
                )
            )
            continue
        term_issues = _check_term(term, tpath, len(rb.inputs))
        out.extend(term_issues)
        fine = resolution.term_problem(term, var) if range_ok and not term_issues else None
        if fine is not None:
            out.append(((*tpath, term_param_path(term)), fine))
    if kind == "output":
        families = {t.is_sugeno for t in var.terms}
        if len(families) > 1:
            sugeno = [t.name for t in var.terms if t.is_sugeno]
            mamdani = [t.name for t in var.terms if not t.is_sugeno]
            out.append(
                (
                    (*base, "terms"),
                    f"output {var.name!r} mixes Sugeno terms ({', '.join(sugeno)}) with "
                    f"membership functions ({', '.join(mamdani)}); all terms of one output must "
                    "be constant/linear (Sugeno) or all membership functions (Mamdani)",
                )
            )
    if var.units is not None:
        why = units_problem(var.units)
        if why:
            out.append(((*base, "units"), f"units of {kind} {var.name!r}: {why}"))
    if kind == "output" and var.default is not None:
        d = var.default
        if not math.isfinite(d) or (range_ok and not var.low <= d <= var.high):
            out.append(
                (
                    (*base, "default"),
                    f"default must be a finite number inside the range [{_fmt(var.low)}, "
                    f"{_fmt(var.high)}], got {_fmt(d)}",
                )
            )
    return out


def _used_in_linear(rb: RuleBase, name: str) -> bool:
    """Whether a ``linear`` output term has a non-zero coefficient for input ``name``."""
    try:
        pos = rb.input_names.index(name)
    except ValueError:
        return False
    return any(
        t.shape == "linear" and len(t.params) == len(rb.inputs) + 1 and t.params[pos] != 0.0
        for v in rb.outputs
        for t in v.terms
    )


def _coverage_gaps(rb: RuleBase) -> list[Issue]:
    """One issue per input with a part of its range where no term is above zero."""
    out: list[Issue] = []
    for var in rb.inputs:
        range_ok = math.isfinite(var.low) and math.isfinite(var.high) and var.low < var.high
        if not (range_ok and var.terms and all(map(_term_is_valid, var.terms))):
            continue
        if any(shape_record(t.shape).mu is None for t in var.terms):
            continue  # a Sugeno output term as an input term: an error of its own
        gaps = uncovered(var)
        if gaps:
            text = ", ".join(
                f"[{_fmt(lo)}, {_fmt(hi)}]" if lo != hi else f"at {_fmt(lo)}" for lo, hi in gaps
            )
            out.append(
                (
                    ("inputs", var.name, "terms"),
                    f"input {var.name!r} is not covered on {text} (no term has membership > 0 "
                    "there; where no rule fires, the outputs take their default, or NaN)",
                )
            )
    return out


# ---------------------------------------------------------------------------- rules


def condition_depth(expr: Expression) -> int:
    """How many and/or levels ``expr`` nests (0 for a single condition); iterative."""
    deepest = 0
    stack: list[tuple[Expression, int]] = [(expr, 0)]
    while stack:
        node, depth = stack.pop()
        if isinstance(node, Compound):
            deepest = max(deepest, depth + 1)
            stack.extend((sub, depth + 1) for sub in node.operands)
    return deepest


def depth_problems(rb: RuleBase) -> list[Issue]:
    """A problem per rule whose condition nests deeper than :data:`MAX_CONDITION_DEPTH`."""
    out: list[Issue] = []
    for k, rule in enumerate(rb.rules):
        depth = condition_depth(rule.antecedent)
        if depth > MAX_CONDITION_DEPTH:
            out.append(
                (
                    ("rules", k, "if"),
                    f"condition nested {depth} and/or levels deep; conditions are limited to "
                    f"{MAX_CONDITION_DEPTH} levels",
                )
            )
    return out


def _check_expression(expr: Expression, rb: RuleBase, base: Path) -> list[Issue]:
    if isinstance(expr, Compound):
        out: list[Issue] = []
        if expr.op not in ("and", "or"):
            out.append((base, f"unknown connective {expr.op!r}; expected 'and' or 'or'"))
        if len(expr.operands) < 2:
            out.append((base, f"'{expr.op}' needs at least 2 operands, got {len(expr.operands)}"))
        for i, sub in enumerate(expr.operands):
            out.extend(_check_expression(sub, rb, (*base, i)))
        return out
    return _check_reference(expr.variable, expr.term, rb, base, want="input")


def _check_reference(name: str, term: str, rb: RuleBase, path: Path, want: str) -> list[Issue]:
    wanted = rb.inputs if want == "input" else rb.outputs
    other = rb.outputs if want == "input" else rb.inputs
    var = next((v for v in wanted if v.name == name), None)
    if var is None:
        if any(v.name == name for v in other):
            if want == "input":
                return [(path, f"{name!r} is an output; conditions (if) may only use inputs")]
            return [(path, f"{name!r} is an input; conclusions (then) may only set outputs")]
        names = [v.name for v in wanted]
        return [
            (
                path,
                f"unknown {want} {name!r}{did_you_mean(name, names)}; "
                f"expected one of {', '.join(names) or '(none)'}",
            )
        ]
    if term not in var.term_names:
        return [
            (
                (*path, "label"),
                f"unknown label {term!r} for {want} {name!r}"
                f"{did_you_mean(term, var.term_names)}; expected one of "
                f"{', '.join(var.term_names)}",
            )
        ]
    return []


def _check_rules(rb: RuleBase) -> list[Issue]:
    out: list[Issue] = []
    if not rb.rules:
        out.append((("rules",), "the rule base has no rules (expected at least one)"))
    too_deep = depth_problems(rb)
    out.extend(too_deep)
    for k, rule in enumerate(rb.rules):
        if not any(path[1] == k for path, _ in too_deep):
            out.extend(_check_expression(rule.antecedent, rb, ("rules", k, "if")))
        if not rule.consequents:
            out.append(
                (("rules", k, "then"), "rule has no conclusion (expected then: {output: label})")
            )
        seen: set[str] = set()
        for j, cons in enumerate(rule.consequents):
            path: Path = ("rules", k, "then", j)
            if cons.variable in seen:
                out.append((path, f"output {cons.variable!r} is set twice in one rule"))
            seen.add(cons.variable)
            out.extend(_check_reference(cons.variable, cons.term, rb, path, want="output"))
        w = rule.weight
        if not (math.isfinite(w) and 0.0 <= w <= 1.0):
            out.append((("rules", k, "weight"), f"weight must be in [0, 1], got {_fmt(w)}"))
    if rb.table is not None:
        t = rb.table
        for key, name, pool, kind in (
            ("rows", t.rows, rb.input_names, "input"),
            ("columns", t.columns, rb.input_names, "input"),
            ("output", t.output, rb.output_names, "output"),
        ):
            if name not in pool:
                out.append(
                    (
                        ("rules", "table", key),
                        f"unknown {kind} {name!r}{did_you_mean(name, pool)}; expected one of "
                        f"{', '.join(pool) or '(none)'}",
                    )
                )
        if t.rows == t.columns:
            out.append(
                (
                    ("rules", "table", "columns"),
                    f"rows and columns must be different inputs, got {t.rows!r} twice",
                )
            )
    return out


# ---------------------------------------------------------------------------- whole model


@dataclass(frozen=True, slots=True)
class Diagnosis:
    """What :func:`diagnose` found: errors make a rule base unusable, warnings do not."""

    errors: list[Issue]
    warnings: list[Issue]


def diagnose(
    rb: RuleBase, allow_gaps: bool | None = None, *, rule_coverage_check: bool = True
) -> Diagnosis:
    """Every problem of ``rb``, split into errors and warnings.

    A coverage gap (part of an input's range where no term is above zero) is a warning when
    ``allow_gaps`` is true, an error when it is false; ``None`` (default) follows
    ``rb.coverage``. A combination of input labels where no rule concluding an output fires
    (:mod:`fuzzkit.fuzzy.rule_coverage`) is a warning when that output has a ``default`` or
    gaps are allowed, else an error; every reader (YAML, .fis, .fcl, .fll) makes this check,
    and so ``fuzzkit validate``, ``eval``, ``surface`` and ``compile`` do.
    ``rule_coverage_check=False`` leaves it out, as :func:`check` and :func:`ensure_valid`
    (which engines call on models built in Python) do: such a model evaluates to the
    default, or NaN, where no rule fires. A term wholly outside its range is an error, a
    shoulder that never reaches 1 inside it a warning (:mod:`fuzzkit.fuzzy.term_placement`).
    Everything else is an error.
    """
    gaps_allowed = rb.coverage == "allow_gaps" if allow_gaps is None else allow_gaps
    errors = _errors(rb)
    gaps = _coverage_gaps(rb)
    # Rule coverage needs valid terms and references. Where an output has a default, a place
    # no rule reaches is a warning under either policy; without one it is an error (NaN).
    check_rules = rule_coverage_check and not errors
    unfired, defaulted = rule_coverage.rule_gaps(rb) if check_rules else ([], [])
    outside, cut_short = term_placement.misplaced_terms(rb) if not errors else ([], [])
    notes = cut_short + defaulted
    if gaps_allowed:
        # where no rule fires the outputs take their default, or NaN: a warning, located
        return Diagnosis(errors + outside, gaps + unfired + notes)
    errors = errors + outside + unfired
    hint = " (set coverage: allow_gaps to make this a warning)"
    return Diagnosis(errors + [(path, message + hint) for path, message in gaps], notes)


def check(rb: RuleBase, allow_gaps: bool | None = None) -> list[Issue]:
    """Every error of ``rb`` as ``(path, message)``; empty when it is usable.

    Coverage gaps count as errors unless allowed (see :func:`diagnose`, which also returns
    them as warnings). Rule coverage is the readers' check, not this one (see
    :func:`diagnose`). See the module docstring for the form of the paths.
    """
    return diagnose(rb, allow_gaps, rule_coverage_check=False).errors


def _errors(rb: RuleBase) -> list[Issue]:
    out: list[Issue] = []
    why = name_problem(rb.name)
    if why:
        out.append((("name",), f"rule-base name: {why}"))
    if not rb.inputs:
        out.append((("inputs",), "expected at least one input"))
    if not rb.outputs:
        out.append((("outputs",), "expected at least one output"))
    seen: dict[str, str] = {}
    for kind, group in (("input", rb.inputs), ("output", rb.outputs)):
        for var in group:
            base: Path = (kind + "s", var.name)
            if var.name in seen:
                # Inputs and outputs share one namespace in generated code.
                out.append(
                    (
                        base,
                        f"duplicate variable name {var.name!r} "
                        f"(already used by an {seen[var.name]})",
                    )
                )
            else:
                seen[var.name] = kind
            out.extend(_check_variable(var, kind, base, rb))

    ops = rb.operators
    for key, value, allowed in (
        ("and", ops.and_, AND_OPERATORS),
        ("or", ops.or_, OR_OPERATORS),
        ("implication", ops.implication, IMPLICATIONS),
        ("aggregation", ops.aggregation, AGGREGATIONS),
    ):
        if value not in allowed:
            out.append(
                (
                    ("operators", key),
                    f"unknown {key} operator {value!r}{did_you_mean(value, allowed)}; "
                    f"expected one of {', '.join(allowed)}",
                )
            )
    if rb.defuzzifier not in DEFUZZIFIERS:
        out.append(
            (
                ("defuzzifier",),
                f"unknown defuzzifier {rb.defuzzifier!r}"
                f"{did_you_mean(rb.defuzzifier, DEFUZZIFIERS)}; "
                f"expected one of {', '.join(DEFUZZIFIERS)}",
            )
        )
    else:
        out.extend(_check_defuzzifier(rb))
    if rb.coverage not in COVERAGE_POLICIES:
        out.append(
            (
                ("coverage",),
                f"unknown coverage policy {rb.coverage!r}"
                f"{did_you_mean(rb.coverage, COVERAGE_POLICIES)}; expected one of "
                f"{', '.join(COVERAGE_POLICIES)}",
            )
        )
    if rb.out_of_range not in OUT_OF_RANGE_POLICIES:
        out.append(
            (
                ("out_of_range",),
                f"unknown out_of_range policy {rb.out_of_range!r}"
                f"{did_you_mean(rb.out_of_range, OUT_OF_RANGE_POLICIES)}; expected one of "
                f"{', '.join(OUT_OF_RANGE_POLICIES)}",
            )
        )
    out.extend(_check_rules(rb))
    if isinstance(rb, Type2RuleBase):
        out.extend(footprint_problems(rb, lambda t, base: _check_term(t, base, len(rb.inputs))))
    return out


def _check_defuzzifier(rb: RuleBase) -> list[Issue]:
    """The defuzzifier fits every output: Sugeno ones need a weighted one, singletons too."""
    out: list[Issue] = []
    d = rb.defuzzifier
    for var in rb.outputs:
        if var.is_sugeno and d not in SUGENO_DEFUZZIFIERS:
            out.append(
                (
                    ("defuzzifier",),
                    f"output {var.name!r} has Sugeno terms (constant/linear), which need "
                    f"defuzzifier {' or '.join(SUGENO_DEFUZZIFIERS)}, got {d!r}",
                )
            )
        elif not var.is_sugeno and d == "weighted_sum":
            out.append(
                (
                    ("defuzzifier",),
                    f"weighted_sum is for Sugeno outputs (constant/linear terms), but output "
                    f"{var.name!r} has membership-function terms; expected another defuzzifier",
                )
            )
        elif not var.is_sugeno and d != "weighted_average":
            for term in var.terms:
                # an unknown shape is reported by the term's own check, at its place
                if term.shape in SHAPE_PARAMS and shape_record(term.shape).impulse:
                    out.append(
                        (
                            ("outputs", var.name, "terms", term.name, "shape"),
                            f"singleton output term {term.name!r} has no area, so defuzzifier "
                            f"{d!r} cannot use it; expected defuzzifier "
                            "weighted_average or a shape with area",
                        )
                    )
    return out


def format_path(path: Path) -> str:
    """``inputs.e.terms.NL`` / ``rules[3].if[0]``: a path as a user reads it."""
    text = ""
    for part in path:
        if isinstance(part, int):
            text += f"[{part}]"
        else:
            # an over-long name is reported by its start (the problem says how long it is)
            shown = part if len(part) <= MAX_NAME_CHARS else part[:20] + "..."
            text += ("." if text else "") + shown
    return text


def as_problems(rb: RuleBase, issues: Iterable[Issue], severity: str = "error") -> list[Problem]:
    """Issues as problems located at ``rb.source.path`` (``<rulebase>`` when built in Python).

    Line 0 (unknown); each message starts with the logical path (e.g. ``inputs.e.terms.NL``).
    """
    file = rb.source.path if rb.source is not None else "<rulebase>"
    return [
        Problem(Location(file), f"{format_path(path)}: {message}", severity)
        for path, message in issues
    ]


def ensure_valid(rb: RuleBase, allow_gaps: bool | None = None) -> None:
    """Raise :class:`~fuzzkit.errors.RuleBaseError` listing every error of ``rb``, if any.

    Coverage gaps are errors unless allowed (``allow_gaps``, or ``rb.coverage`` when ``None``).
    Locations are those of :func:`as_problems`.
    """
    issues = check(rb, allow_gaps)
    if issues:
        raise RuleBaseError(as_problems(rb, issues))
