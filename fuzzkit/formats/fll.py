"""fuzzylite's FLL files: import to and export from fuzzkit's model.

FLL is line based: ``Engine:``, ``InputVariable:``, ``OutputVariable:`` and ``RuleBlock:``
open sections, each followed by ``key: value`` lines; ``#`` starts a comment. Semantics kept:

* ``lock-range: true`` on the inputs clamps them (``out_of_range: clamp``), ``false``
  evaluates terms where the input is (``extend``); the inputs must agree;
* an output's ``default`` applies where no rule fires (``nan`` is fuzzkit's no default);
* ``aggregation`` and ``defuzzifier`` are per output in FLL and global in fuzzkit, so all
  outputs must agree; integral defuzzifiers carry a resolution, which fuzzkit ignores (its
  engine is exact) and writes as :data:`RESOLUTION`;
* Sugeno outputs (``Constant``, ``Linear``) with ``WeightedAverage``/``WeightedSum`` and
  ``aggregation: none``: every rule is weighted separately.

Terms map exactly, as the shape registry (:mod:`fuzzkit.fuzzy.shapes`) spells them:
``Triangle a b c``, ``Trapezoid a b c d``, ``Ramp start end`` (a shoulder), ``Gaussian mean
sigma``, ``Bell centre width slope``, ``Sigmoid inflection slope``, the smooth
``GaussianProduct meanA sigmaA meanB sigmaB``, ``SShape start end``, ``ZShape start end``,
``PiShape bottomLeft topLeft topRight bottomRight``, ``SigmoidDifference left rising falling
right`` and ``SigmoidProduct left rising falling right``, ``Discrete`` point lists drawing a
triangle, trapezoid or shoulder, ``Constant v`` and ``Linear c_1 ... c_n c_0``. Other
terms, hedges, activation methods other than ``General``, ``lock-previous: true`` and disabled
parts are refused with their line and column.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path as FsPath

from fuzzkit.errors import Problem
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
    write_named,
)
from fuzzkit.formats.rule_text import parse_rule, rule_text
from fuzzkit.fuzzy import shapes
from fuzzkit.fuzzy.model import Operators, Rule, RuleBase, Term, Variable

SUFFIX = ".fll"
#: Resolution written for fuzzylite's integral defuzzifiers (fuzzkit's own engine is exact).
RESOLUTION = 10000

_AND = {"Minimum": "min", "AlgebraicProduct": "product"}
_OR = {"Maximum": "max", "AlgebraicSum": "probabilistic_sum"}
_IMP = {"Minimum": "min", "AlgebraicProduct": "product"}
_AGG = {"Maximum": "max", "BoundedSum": "bounded_sum", "AlgebraicSum": "probabilistic_sum"}
_DEFUZZ = {
    "Centroid": "centroid",
    "Bisector": "bisector",
    "MeanOfMaximum": "mean_of_maximum",
    "SmallestOfMaximum": "smallest_of_maximum",
    "LargestOfMaximum": "largest_of_maximum",
    "WeightedAverage": "weighted_average",
    "WeightedSum": "weighted_sum",
}
#: fuzzylite terms fuzzkit's model does not have (refused by name); those it has are the
#: shape registry's (fuzzkit.fuzzy.shapes).
_OTHER_TERMS = frozenset(
    [
        "Rectangle",
        "Cosine",
        "Concave",
        "Spike",
        "Binary",
        "Function",
        "Activated",
        "Aggregated",
    ]
)
_KEYS = {
    "Engine": {"description"},
    "InputVariable": {"description", "enabled", "range", "lock-range", "term"},
    "OutputVariable": {
        "description",
        "enabled",
        "range",
        "lock-range",
        "aggregation",
        "accumulation",
        "defuzzifier",
        "default",
        "lock-previous",
        "term",
    },
    "RuleBlock": {
        "description",
        "enabled",
        "conjunction",
        "disjunction",
        "implication",
        "activation",
        "rule",
    },
}


@dataclass
class _Entry:
    key: str
    value: str
    line: int
    col: int


@dataclass
class _Block:
    kind: str
    name: str
    line: int
    col: int
    entries: list[_Entry] = field(default_factory=list)

    def get(self, key: str) -> _Entry | None:
        return next((e for e in self.entries if e.key == key), None)


def _blocks(text: str, found: Collector) -> list[_Block]:
    blocks: list[_Block] = []
    for n, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0].rstrip()
        stripped = line.strip()
        if not stripped:
            continue
        col = line.index(stripped[0]) + 1
        key, colon, value = stripped.partition(":")
        vcol = col + len(key) + 1 + (len(value) - len(value.lstrip()))
        value = value.strip()
        if not colon:
            found.add(n, col, f"expected 'key: value', got {stripped!r}")
            continue
        if key in _KEYS:
            blocks.append(_Block(key, value, n, vcol))
            continue
        if not blocks:
            found.add(n, col, f"expected 'Engine: name' before {key!r}")
            continue
        block = blocks[-1]
        if key not in _KEYS[block.kind]:
            found.add(
                n,
                col,
                f"unknown key {key!r} in {block.kind}; expected one of "
                f"{', '.join(sorted(_KEYS[block.kind]))}",
            )
            continue
        if key not in ("term", "rule") and block.get(key) is not None:
            found.add(n, col, f"key {key!r} appears twice in {block.kind} {block.name!r}")
            continue
        block.entries.append(_Entry(key, value, n, vcol))
    return blocks


def _bool(e: _Entry | None, found: Collector, default: bool) -> bool:
    if e is None:
        return default
    if e.value not in ("true", "false"):
        found.add(e.line, e.col, f"{e.key}: expected true or false, got {e.value!r}")
        return default
    return e.value == "true"


def _numbers(text: str, e: _Entry, found: Collector) -> list[float] | None:
    out = []
    for token in text.split():
        x = parse_number(token)
        if x is None:
            found.add(e.line, e.col, f"{e.key}: expected numbers, got {token!r}")
            return None
        out.append(x)
    return out


def named_term(
    name: str,
    cls: str,
    args: list[float],
    sugeno_out: bool,
    n_inputs: int,
) -> Term | str:
    """A fuzzylite term ``name Class args`` (as FLL and FCL write it) as a fuzzkit term, or why not.

    ``sugeno_out`` says the term belongs to an output of a Sugeno system, which takes exactly
    the ``Constant`` and ``Linear`` terms; ``n_inputs`` is the number of coefficients a
    ``Linear`` term needs, less its constant.
    """
    known = shapes.spellings("fll")
    if cls in _OTHER_TERMS:
        return f"{cls} is not in fuzzkit's model (refused, not approximated)"
    if cls not in (*known, "Discrete"):
        return f"unknown term class {cls!r}; expected one of {', '.join(known)}, Discrete"
    if (cls in known and known[cls][0][0].sugeno) != sugeno_out:
        return f"{cls}: Constant and Linear terms belong to Sugeno outputs, which take no others"
    if cls == "Discrete":
        if len(args) % 2:
            return f"Discrete needs x y pairs, got {len(args)} numbers"
        return points_to_term(name, list(zip(args[::2], args[1::2], strict=True)))
    shape, spelling = known[cls][0]
    if spelling.arity is None:  # Linear: one coefficient per input, then the constant
        if len(args) != n_inputs + 1:
            return (
                f"{cls} needs {n_inputs + 1} coefficients (one per input, then the "
                f"constant), got {len(args)}"
            )
        return read_named("fll", name, cls, args)
    n = spelling.arity
    if len(args) == n + 1 and not shape.sugeno:
        if args[-1] != 1.0:  # fuzzylite's optional height
            return f"height {fmt(args[-1])} cannot be expressed (fuzzkit terms reach 1)"
        args = args[:-1]
    if len(args) != n:
        return f"{cls} needs {n} parameters, got {len(args)}"
    return read_named("fll", name, cls, args)


def _term(e: _Entry, found: Collector, sugeno_out: bool, n_inputs: int) -> Term | None:
    parts = e.value.split(None, 2)
    if len(parts) < 2:
        found.add(e.line, e.col, f"term: expected 'name Class parameters', got {e.value!r}")
        return None
    args = _numbers(parts[2] if len(parts) > 2 else "", e, found)
    if args is None:
        return None
    term = named_term(parts[0], parts[1], args, sugeno_out, n_inputs)
    if isinstance(term, str):
        found.add(e.line, e.col, f"term {parts[0]!r}: {term}")
        return None
    return term


def _one_of(
    e: _Entry | None, table: dict[str, str], found: Collector, what: str, allow_none: bool = False
) -> str | None:
    if e is None or (allow_none and e.value in ("none", "")):
        return None
    word = e.value.split()[0] if e.value else ""
    if word not in table:
        found.add(
            e.line,
            e.col,
            f"{what}: {e.value!r} cannot be expressed in fuzzkit; expected "
            f"one of {', '.join(table)}",
        )
        return None
    return table[word]


def _variable(
    b: _Block,
    kind: str,
    found: Collector,
    sugeno: bool,
    n_inputs: int,
) -> Variable | None:
    if not _bool(b.get("enabled"), found, True):
        e = b.get("enabled")
        found.add(
            e.line if e else b.line,
            e.col if e else b.col,
            f"{kind} {b.name!r} is disabled (fuzzkit has no disabled variables)",
        )
    rng_e = b.get("range")
    if rng_e is None:
        found.add(b.line, b.col, f"{kind} {b.name!r}: missing 'range: low high'")
        return None
    rng = _numbers(rng_e.value, rng_e, found)
    if rng is None:
        return None
    if len(rng) != 2:
        found.add(rng_e.line, rng_e.col, f"range: expected 2 numbers 'low high', got {len(rng)}")
        return None
    base = (kind + "s", b.name)
    found.mark(base, b.line, b.col)
    found.mark((*base, "range"), rng_e.line, rng_e.col)
    terms: list[Term] = []
    seen: set[str] = set()
    for e in b.entries:
        if e.key != "term":
            continue
        term = _term(e, found, kind == "output" and sugeno, n_inputs)
        if term is None:
            continue
        if term.name in seen:
            found.add(
                e.line,
                e.col,
                f"term name {term.name!r} appears twice in {kind} "
                f"{b.name!r}; a rule naming it would be ambiguous",
            )
            continue
        seen.add(term.name)
        found.mark((*base, "terms", term.name), e.line, e.col)
        terms.append(term)
    default: float | None = None
    if kind == "output":
        d = b.get("default")
        if d is not None:
            value = parse_number(d.value)
            if value is None:
                found.add(d.line, d.col, f"default: expected a number or nan, got {d.value!r}")
            elif not math.isnan(value):
                default = value
            found.mark((*base, "default"), d.line, d.col)
        e = b.get("lock-previous")
        if e is not None and _bool(e, found, False):
            found.add(
                e.line,
                e.col,
                "lock-previous: true (keep the last value when no rule "
                "fires) cannot be expressed in fuzzkit; use a default",
            )
        e = b.get("lock-range")
        if sugeno and e is not None and _bool(e, found, False):
            found.add(
                e.line,
                e.col,
                "lock-range: true on a Sugeno output (fuzzkit does not clamp Sugeno outputs)",
            )
    return Variable(b.name, rng[0], rng[1], tuple(terms), default)


def _same(entries: list[_Entry], found: Collector, what: str) -> _Entry | None:
    """The one value all outputs give for ``what`` (a problem if they differ)."""
    if not entries:
        return None
    first = entries[0]
    for e in entries[1:]:
        if e.value.split()[:1] != first.value.split()[:1]:
            found.add(
                e.line,
                e.col,
                f"{what}: every output must use the same one in fuzzkit "
                f"(first was {first.value!r})",
            )
    return first


def loads(text: str, source: str = "<string>") -> RuleBase:
    """Parse the text of a file of this format (see :func:`loads_with_warnings`)."""
    return loads_with_warnings(text, source)[0]


def loads_with_warnings(text: str, source: str = "<string>") -> tuple[RuleBase, list[Problem]]:
    """Parse FLL text into a rule base; ``source`` names it in messages.

    Returns the rule base and the warnings (coverage gaps, located; see
    :func:`fuzzkit.formats.foreign_common.finish`).

    Raises
    ------
    RuleBaseError
        Every problem as ``source:line:col: message``.
    """
    found = Collector(source)
    blocks = _blocks(text, found)
    engines = [b for b in blocks if b.kind == "Engine"]
    if len(engines) != 1 or blocks[0].kind != "Engine":
        found.add(1, 1, "expected one 'Engine: name' line first (is this an .fll file?)")
        found.fail()
    engine = engines[0]
    found.mark(("name",), engine.line, engine.col)
    found.mark((), engine.line, 1)  # problems of the whole rule base
    ins = [b for b in blocks if b.kind == "InputVariable"]
    outs = [b for b in blocks if b.kind == "OutputVariable"]
    rule_blocks = [b for b in blocks if b.kind == "RuleBlock"]
    out_terms = [e for b in outs for e in b.entries if e.key == "term"]
    sugeno = any(e.value.split()[1:2] in (["Constant"], ["Linear"]) for e in out_terms)
    inputs = [v for b in ins if (v := _variable(b, "input", found, False, len(ins))) is not None]
    outputs = [
        v for b in outs if (v := _variable(b, "output", found, sugeno, len(ins))) is not None
    ]
    locks = {_bool(b.get("lock-range"), found, False) for b in ins}
    if len(locks) > 1:
        found.add(
            ins[0].line, 1, "lock-range differs between inputs; fuzzkit clamps all inputs or none"
        )
    agg_e = _same(
        [e for b in outs if (e := b.get("aggregation") or b.get("accumulation"))],
        found,
        "aggregation",
    )
    def_e = _same([e for b in outs if (e := b.get("defuzzifier"))], found, "defuzzifier")
    if def_e is None:
        found.add(outs[0].line if outs else 1, 1, "missing 'defuzzifier:' in OutputVariable")
    defuzz = _one_of(def_e, _DEFUZZ, found, "defuzzifier")
    if def_e is not None:
        found.mark(("defuzzifier",), def_e.line, def_e.col)
        words = def_e.value.split()
        if defuzz in SUGENO_DEFUZZIFIERS and words[1:] not in ([], ["Automatic"], ["TakagiSugeno"]):
            found.add(
                def_e.line,
                def_e.col,
                f"defuzzifier: {def_e.value!r} (fuzzkit's weighted "
                "defuzzifiers are Takagi-Sugeno; Tsukamoto is not supported)",
            )
        if (defuzz in SUGENO_DEFUZZIFIERS) != sugeno and defuzz is not None:
            found.add(
                def_e.line,
                def_e.col,
                f"defuzzifier {words[0]} does not go with "
                f"{'Sugeno' if sugeno else 'Mamdani'} output terms",
            )
    agg = _one_of(agg_e, _AGG, found, "aggregation", allow_none=True)
    if agg is None and not sugeno and (agg_e is None or agg_e.value in ("none", "")):
        found.add(
            agg_e.line if agg_e else 1,
            agg_e.col if agg_e else 1,
            "aggregation: a Mamdani output needs one (Maximum, BoundedSum, AlgebraicSum)",
        )
    if sugeno and agg is not None and agg_e is not None:
        found.add(
            agg_e.line,
            agg_e.col,
            "aggregation: a Sugeno output weights every rule "
            "separately in fuzzkit; expected 'aggregation: none'",
        )
    if len(rule_blocks) != 1:
        found.add(
            rule_blocks[1].line if len(rule_blocks) > 1 else len(text.splitlines()) or 1,
            1,
            f"expected one RuleBlock, got {len(rule_blocks)} (truncated file?)"
            if not rule_blocks
            else "several RuleBlocks cannot be expressed in fuzzkit",
        )
        found.fail()
    rb_block = rule_blocks[0]
    found.mark(("rules",), rb_block.line, 1)
    if not _bool(rb_block.get("enabled"), found, True):
        found.add(rb_block.line, 1, "the RuleBlock is disabled")
    and_ = _one_of(rb_block.get("conjunction"), _AND, found, "conjunction", allow_none=True)
    or_ = _one_of(rb_block.get("disjunction"), _OR, found, "disjunction", allow_none=True)
    imp = _one_of(rb_block.get("implication"), _IMP, found, "implication", allow_none=True)
    act = rb_block.get("activation")
    if act is not None and act.value not in ("General", "none", ""):
        found.add(
            act.line,
            act.col,
            f"activation: {act.value!r} cannot be expressed in fuzzkit (every rule fires: General)",
        )
    for key, path_key in (
        ("conjunction", "and"),
        ("disjunction", "or"),
        ("implication", "implication"),
    ):
        e = rb_block.get(key)
        if e is not None:
            found.mark(("operators", path_key), e.line, e.col)
    if agg_e is not None:
        found.mark(("operators", "aggregation"), agg_e.line, agg_e.col)
    by_in = {v.name: v for v in inputs}
    by_out = {v.name: v for v in outputs}
    rules: list[Rule] = []
    for e in rb_block.entries:
        if e.key != "rule":
            continue
        rule = parse_rule(e.value, e.line, e.col, by_in, by_out, found)
        if rule is not None:
            found.mark(("rules", len(rules)), e.line, e.col)
            rules.append(rule)
    found.raise_if_any()
    desc = engine.get("description")
    rb = RuleBase(
        name=engine.name,
        inputs=tuple(inputs),
        outputs=tuple(outputs),
        rules=tuple(rules),
        operators=Operators(and_ or "min", or_ or "max", imp or "min", agg or "max"),
        defuzzifier=defuzz or "centroid",
        out_of_range="clamp" if locks == {True} else "extend",
        description=desc.value if desc else "",
    )
    return finish(rb, found, text)


def load(path: str | FsPath) -> RuleBase:
    """Read an ``.fll`` file (see :func:`loads`)."""
    return loads(read_text(path, "an .fll file"), str(path))


def load_with_warnings(path: str | FsPath) -> tuple[RuleBase, list[Problem]]:
    """:func:`load`, also returning the warnings (coverage gaps), located."""
    return loads_with_warnings(read_text(path, "an .fll file"), str(path))


# ---------------------------------------------------------------------------- export


def term_body(term: Term) -> str | None:
    """``Class params`` of a term as fuzzylite writes it (FLL and named FCL), else None."""
    return write_named("fll", term)


def _term_text(term: Term) -> str | None:
    body = term_body(term)
    return None if body is None else f"{term.name} {body}"


def refusals(rb: RuleBase) -> list[str]:
    """What in ``rb`` FLL cannot express (export is refused)."""
    out: list[str] = []
    sugeno = is_sugeno(rb)
    if (rb.defuzzifier in SUGENO_DEFUZZIFIERS) != sugeno:
        out.append(
            f"defuzzifier {rb.defuzzifier!r} with {'Sugeno' if sugeno else 'Mamdani'} "
            "terms (fuzzylite's weighted defuzzifiers on Mamdani terms are Tsukamoto's, "
            "not fuzzkit's term centres)"
        )
    for var in rb.inputs + rb.outputs:
        for term in var.terms:
            if _term_text(term) is None:
                out.append(f"term {var.name}.{term.name}: shape {term.shape!r}")
    return out


def dumps(rb: RuleBase, *, allow_loss: bool = False) -> str:
    """The FLL text of ``rb``; ``loads(dumps(rb))`` equals ``rb`` (descriptions on one line).

    ``allow_loss`` is accepted for symmetry with the other formats: FLL holds every
    semantic property of a rule base it can express at all.

    Raises
    ------
    ExportError
        ``rb`` holds something FLL cannot express (:func:`refusals`).
    """
    del allow_loss
    problems = refusals(rb)
    if problems:
        raise ExportError("fll", rb.name, problems)
    sugeno = is_sugeno(rb)
    rev = {v: k for k, v in _AGG.items()}
    rev_def = {v: k for k, v in _DEFUZZ.items()}
    lines = [f"Engine: {rb.name}"]
    if rb.description:
        lines.append(f"description: {' '.join(rb.description.split())}")
    lock = "true" if rb.out_of_range == "clamp" else "false"
    for var in rb.inputs:
        lines += [
            f"InputVariable: {var.name}",
            "  enabled: true",
            f"  range: {fmt(var.low)} {fmt(var.high)}",
            f"  lock-range: {lock}",
        ]
        lines += [f"  term: {_term_text(t)}" for t in var.terms]
    if sugeno:
        defuzz = f"{rev_def[rb.defuzzifier]} TakagiSugeno"
        agg = "none"
    else:
        defuzz = f"{rev_def[rb.defuzzifier]} {RESOLUTION}"  # all five integrate in fuzzylite
        agg = rev[rb.operators.aggregation]
    for var in rb.outputs:
        lines += [
            f"OutputVariable: {var.name}",
            "  enabled: true",
            f"  range: {fmt(var.low)} {fmt(var.high)}",
            "  lock-range: false",
            f"  aggregation: {agg}",
            f"  defuzzifier: {defuzz}",
            f"  default: {'nan' if var.default is None else fmt(var.default)}",
            "  lock-previous: false",
        ]
        lines += [f"  term: {_term_text(t)}" for t in var.terms]
    ops = rb.operators
    lines += [
        "RuleBlock: rules",
        "  enabled: true",
        f"  conjunction: {next(k for k, v in _AND.items() if v == ops.and_)}",
        f"  disjunction: {next(k for k, v in _OR.items() if v == ops.or_)}",
        f"  implication: {next(k for k, v in _IMP.items() if v == ops.implication)}",
        "  activation: General",
    ]
    lines += [f"  rule: {rule_text(r)}" for r in rb.rules]
    return "\n".join(lines) + "\n"


def _write(rb: RuleBase, allow_loss: bool, dialect: str) -> str:
    return dumps(rb, allow_loss=allow_loss)


#: The format as :data:`fuzzkit.formats.registry.FORMATS` lists it.
FORMAT = ForeignFormat(
    name="fll",
    suffix=SUFFIX,
    label="fuzzylite .fll",
    first_word="Engine:",
    read=load_with_warnings,
    write=_write,
)
