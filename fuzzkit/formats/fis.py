"""MATLAB Fuzzy Logic Toolbox ``.fis`` files: import to and export from fuzzkit's model.

Semantics kept from MATLAB:

* inputs are evaluated where they are, without clamping: an imported rule base has
  ``out_of_range: extend``;
* when no rule fires, an output is the middle of its range (MATLAB's ``evalfis``): imported
  outputs get that ``default``;
* in a Sugeno file ``ImpMethod`` and ``AggMethod`` are ignored (as MATLAB does);
* rule lines are numeric: ``1 -2, 3 (0.5) : 1`` is "if in1 is mf1 and in2 is not mf2 then
  out1 is mf3 with weight 0.5"; ``0`` is "don't care" (input) or "no conclusion" (output), the
  last number is the connective (1 AND, 2 OR).

Shapes map exactly, as the shape registry (:mod:`fuzzkit.fuzzy.shapes`) spells them:
``trimf [a b c]`` = triangle, ``trapmf [a b c d]`` = trapezoid (with ``-inf -inf`` or
``inf inf`` ends it is a shoulder; ``linzmf``/``linsmf`` and fuzzylite's ``rampmf`` are
shoulders too), ``gaussmf [sigma c]``, ``gbellmf [a b c]``, ``sigmf [a c]``, the smooth
``gauss2mf [sigma1 c1 sigma2 c2]``, ``smf [a b]``, ``zmf [a b]``, ``pimf [a b c d]``,
``dsigmf [a1 c1 a2 c2]`` and ``psigmf [a1 c1 a2 c2]``, and the Sugeno output terms
``constant [v]`` and ``linear [c_1 ... c_n c_0]``. Everything else (custom functions, unbounded
``sum`` aggregation, hedges, negated conclusions) is refused with its line and column, never
approximated.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path as FsPath

from fuzzkit.errors import Problem, did_you_mean
from fuzzkit.formats.foreign_common import (
    SUGENO_DEFUZZIFIERS,
    Collector,
    ExportError,
    ForeignFormat,
    combine,
    finish,
    flat_conditions,
    fmt,
    is_sugeno,
    parse_number,
    read_named,
    read_text,
)
from fuzzkit.fuzzy import shapes
from fuzzkit.fuzzy.model import (
    Consequent,
    Expression,
    Operators,
    Proposition,
    Rule,
    RuleBase,
    Term,
    Variable,
)

SUFFIX = ".fis"

_AND = {"min": "min", "prod": "product"}
_OR = {"max": "max", "probor": "probabilistic_sum"}
_IMP = {"min": "min", "prod": "product"}
_AGG = {"max": "max", "probor": "probabilistic_sum"}
_DEFUZZ = {
    "centroid": "centroid",
    "bisector": "bisector",
    "mom": "mean_of_maximum",
    "som": "smallest_of_maximum",
    "lom": "largest_of_maximum",
    "wtaver": "weighted_average",
    "wtsum": "weighted_sum",
}
_WHY_NOT = {
    "sum": "aggregation 'sum' is MATLAB's unbounded sum; fuzzkit has bounded_sum "
    "(min(1, a + b)), which differs where the sum exceeds 1",
}
#: MATLAB membership functions fuzzkit's model does not have (refused by name); those it
#: has are the shape registry's (fuzzkit.fuzzy.shapes).
_OTHER_MFS = frozenset(
    [
        "trimf2",
        "trapmf2",
        "gaussmf2",
        "gbellmf2",
        "sigmf2",
        "cosinemf",
        "concavemf",
        "spikemf",
        "discretemf",
        "binarymf",
        "rectanglemf",
        "rectmf",
    ]
)
_SYSTEM_KEYS = (
    "Name",
    "Type",
    "Version",
    "NumInputs",
    "NumOutputs",
    "NumRules",
    "AndMethod",
    "OrMethod",
    "ImpMethod",
    "AggMethod",
    "DefuzzMethod",
)
_VAR_KEYS = ("Name", "Range", "NumMFs")
_SECTION = re.compile(r"\[(\w+?)(\d*)\]\Z")
_MF = re.compile(r"'([^']*)'\s*:\s*'([^']*)'\s*,\s*\[([^\]]*)\]\s*\Z")
_RULE = re.compile(r"([^()]*)\(([^()]*)\)\s*:\s*(\S+)\s*\Z")


@dataclass
class _Value:
    text: str
    line: int
    col: int


@dataclass
class _Section:
    name: str
    line: int
    keys: dict[str, _Value]
    rules: list[_Value]


def _split_sections(text: str, found: Collector) -> list[_Section]:
    sections: list[_Section] = []
    seen: set[str] = set()
    for n, raw in enumerate(text.splitlines(), start=1):
        stripped = raw.strip()
        if not stripped or stripped.startswith(("%", "#", "//")):
            continue
        col = raw.index(stripped[0]) + 1
        if stripped.startswith("["):
            if _SECTION.match(stripped) is None or (
                sections and sections[-1].name == "Rules" and not stripped.endswith("]")
            ):
                found.add(n, col, f"expected a section header like [Input1], got {stripped!r}")
                continue
            name = stripped[1:-1]
            if name in seen:
                found.add(n, col, f"section [{name}] appears twice")
            seen.add(name)
            sections.append(_Section(name, n, {}, []))
            continue
        if not sections:
            found.add(n, col, f"expected [System] before anything else, got {stripped!r}")
            continue
        sec = sections[-1]
        if sec.name == "Rules":
            sec.rules.append(_Value(stripped, n, col))
            continue
        key, eq, value = stripped.partition("=")
        if not eq:
            found.add(n, col, f"expected key=value in [{sec.name}], got {stripped!r}")
            continue
        key = key.strip()
        if key in sec.keys:
            found.add(n, col, f"key {key!r} appears twice in [{sec.name}]")
            continue
        vcol = col + len(stripped) - len(value.lstrip())
        sec.keys[key] = _Value(value.strip(), n, vcol)
    return sections


def _quoted(v: _Value, found: Collector, what: str) -> str | None:
    if len(v.text) >= 2 and v.text[0] == v.text[-1] == "'":
        return v.text[1:-1]
    found.add(v.line, v.col, f"{what}: expected a quoted string like 'name', got {v.text!r}")
    return None


def _count(v: _Value, found: Collector, what: str) -> int | None:
    x = parse_number(v.text)
    if x is None or not x.is_integer() or x < 0:
        found.add(v.line, v.col, f"{what}: expected a whole number >= 0, got {v.text!r}")
        return None
    return int(x)


def _vector(body: str, line: int, col: int, found: Collector, what: str) -> list[float] | None:
    values: list[float] = []
    for token in body.replace(",", " ").split():
        x = parse_number(token)
        if x is None:
            found.add(line, col, f"{what}: expected numbers, got {token!r}")
            return None
        values.append(x)
    return values


def _range(v: _Value, found: Collector, what: str) -> tuple[float, float] | None:
    if not (v.text.startswith("[") and v.text.endswith("]")):
        found.add(v.line, v.col, f"{what}: expected [low high], got {v.text!r}")
        return None
    values = _vector(v.text[1:-1], v.line, v.col, found, what)
    if values is None:
        return None
    if len(values) != 2:
        found.add(v.line, v.col, f"{what}: expected 2 numbers [low high], got {len(values)}")
        return None
    return values[0], values[1]


def _mf_term(
    name: str, kind: str, p: list[float], sugeno_output: bool, n_inputs: int
) -> Term | str:
    """One MATLAB membership function as a fuzzkit term, or why it cannot be one."""
    known = shapes.spellings("fis")
    if kind in _OTHER_MFS:
        return f"membership function {kind!r} is not in fuzzkit's model (refused, not approximated)"
    if kind not in known:
        hint = did_you_mean(kind, [*known, *_OTHER_MFS])
        return f"unknown or custom membership function {kind!r}{hint} (refused, not approximated)"
    shape, spelling = known[kind][0]
    count = spelling.arity if spelling.arity is not None else n_inputs + 1  # linear: c_i, c_0
    if len(p) != count:
        return f"{kind} needs {count} parameters, got {len(p)}"
    if shape.sugeno and not sugeno_output:
        return f"{kind!r} terms are Sugeno outputs only (in a Type='sugeno' file)"
    if sugeno_output and not shape.sugeno:
        return f"a Sugeno output term must be 'constant' or 'linear', got {kind!r}"
    return read_named("fis", name, kind, p)


def _variable(
    sec: _Section,
    kind: str,
    found: Collector,
    sugeno: bool,
    n_inputs: int,
    incomplete: dict[str, int],
) -> Variable | None:
    """One [InputN] or [OutputN]; a variable whose MFs were not all read is entered in
    ``incomplete`` with its NumMFs (its terms then number differently from the file's)."""
    where = f"[{sec.name}]"
    for key in sec.keys:
        if key not in _VAR_KEYS and re.fullmatch(r"MF\d+", key) is None:
            v = sec.keys[key]
            found.add(v.line, 1, f"{where}: unknown key {key!r}; expected Name, Range, NumMFs, MFn")
    missing = [k for k in _VAR_KEYS if k not in sec.keys]
    if missing:
        found.add(sec.line, 1, f"{where}: missing {', '.join(missing)} (truncated file?)")
        return None
    name = _quoted(sec.keys["Name"], found, f"{where} Name")
    rng = _range(sec.keys["Range"], found, f"{where} Range")
    n_mfs = _count(sec.keys["NumMFs"], found, f"{where} NumMFs")
    if name is None or rng is None or n_mfs is None:
        return None
    base = (kind + "s", name)
    found.mark(base, sec.keys["Name"].line, sec.keys["Name"].col)
    found.mark((*base, "range"), sec.keys["Range"].line, sec.keys["Range"].col)
    terms: list[Term] = []
    seen: dict[str, int] = {}
    # A count is checked against the lines there are, never looped over: NumMFs=1e18 is one
    # problem (the first missing MF), not an endless loop.
    n_present = sum(1 for k in sec.keys if re.fullmatch(r"MF\d+", k))
    complete = True  # every MF read: else the rules' term numbers cannot be trusted
    for i in range(1, min(n_mfs, n_present + 1) + 1):
        mf = sec.keys.get(f"MF{i}")
        if mf is None:
            found.add(
                sec.line, 1, f"{where}: NumMFs={n_mfs} but MF{i} is missing (truncated file?)"
            )
            complete = False
            continue
        m = _MF.match(mf.text)
        if m is None:
            found.add(
                mf.line, mf.col, f"{where} MF{i}: expected 'name':'type',[params], got {mf.text!r}"
            )
            complete = False
            continue
        tname, mf_kind = m.group(1), m.group(2)
        params = _vector(m.group(3), mf.line, mf.col + m.start(3), found, f"{where} MF{i}")
        if params is None:
            complete = False
            continue
        if tname in seen:
            found.add(
                mf.line,
                mf.col,
                f"{where} MF{i}: term name {tname!r} is already MF{seen[tname]} of {name!r}; "
                "a rule-base name must be unambiguous",
            )
            complete = False
            continue
        seen[tname] = i
        term = _mf_term(tname, mf_kind, params, kind == "output" and sugeno, n_inputs)
        if isinstance(term, str):
            found.add(mf.line, mf.col, f"{where} MF{i} ({tname!r}): {term}")
            complete = False
            continue
        found.mark((*base, "terms", tname), mf.line, mf.col)
        terms.append(term)
    extra = [k for k in sec.keys if re.fullmatch(r"MF\d+", k) and not 1 <= int(k[2:]) <= n_mfs]
    for k in extra:
        found.add(sec.keys[k].line, 1, f"{where}: {k} is beyond NumMFs={n_mfs}")
    if not complete:
        # a term is missing: the rules number the terms, so they are checked against the
        # declared count, not the terms read (one mistake, one message)
        incomplete[name] = n_mfs
    default = (rng[0] + rng[1]) / 2 if kind == "output" else None
    return Variable(name, rng[0], rng[1], tuple(terms), default)


def _index(token: str) -> int | None:
    x = parse_number(token)
    if x is None or not math.isfinite(x) or not x.is_integer():
        return None
    return int(x)


def _rule(
    v: _Value,
    k: int,
    inputs: list[Variable],
    outputs: list[Variable],
    found: Collector,
    incomplete: dict[str, int],
) -> Rule | None:
    m = _RULE.match(v.text)
    if m is None:
        found.add(
            v.line,
            v.col,
            f"rule {k + 1}: expected 'in1 in2 ..., out1 ... (weight) : connective', got {v.text!r}",
        )
        return None
    body, wtext, ctext = m.group(1), m.group(2).strip(), m.group(3)
    parts = body.split(",")
    if len(parts) > 2:
        found.add(v.line, v.col, f"rule {k + 1}: expected one ',' between inputs and outputs")
        return None
    tokens = [t.split() for t in parts]
    ant, cons = (
        (tokens[0], tokens[1])
        if len(tokens) == 2
        else (tokens[0][: len(inputs)], tokens[0][len(inputs) :])
    )
    if len(ant) != len(inputs) or len(cons) != len(outputs):
        found.add(
            v.line,
            v.col,
            f"rule {k + 1}: expected {len(inputs)} input and "
            f"{len(outputs)} output indices, got {len(ant)} and {len(cons)}",
        )
        return None
    weight = parse_number(wtext)
    if weight is None:
        found.add(
            v.line, v.col + m.start(2), f"rule {k + 1}: weight must be a number, got {wtext!r}"
        )
        return None
    conn = _index(ctext)
    if conn not in (1, 2):
        found.add(
            v.line,
            v.col + m.start(3),
            f"rule {k + 1}: connective must be 1 (AND) or 2 (OR), got {ctext!r}",
        )
        return None
    ok = True
    props: list[Expression] = []
    for var, token in zip(inputs, ant, strict=True):
        idx = _index(token)
        if idx is None:
            found.add(
                v.line,
                v.col,
                f"rule {k + 1}: input {var.name!r}: index {token!r} is not a "
                "whole number (hedges are not supported)",
            )
            ok = False
        elif abs(idx) > incomplete.get(var.name, len(var.terms)):
            found.add(
                v.line,
                v.col,
                f"rule {k + 1}: input {var.name!r} has "
                f"{incomplete.get(var.name, len(var.terms))} terms, the rule uses term {abs(idx)}",
            )
            ok = False
        elif var.name in incomplete:
            ok = False  # the term's problem is already reported
        elif idx != 0:
            props.append(Proposition(var.name, var.terms[abs(idx) - 1].name, idx < 0))
    then: list[Consequent] = []
    for var, token in zip(outputs, cons, strict=True):
        idx = _index(token)
        if idx is None or idx < 0:
            found.add(
                v.line,
                v.col,
                f"rule {k + 1}: output {var.name!r}: index {token!r}: "
                "negated or hedged conclusions cannot be expressed in fuzzkit",
            )
            ok = False
        elif idx > incomplete.get(var.name, len(var.terms)):
            found.add(
                v.line,
                v.col,
                f"rule {k + 1}: output {var.name!r} has "
                f"{incomplete.get(var.name, len(var.terms))} terms, the rule uses term {idx}",
            )
            ok = False
        elif var.name in incomplete:
            ok = False  # the term's problem is already reported
        elif idx != 0:
            then.append(Consequent(var.name, var.terms[idx - 1].name))
    if ok and not props:
        found.add(v.line, v.col, f"rule {k + 1}: every input index is 0 (a rule needs a condition)")
        ok = False
    if ok and not then:
        found.add(v.line, v.col, f"rule {k + 1}: every output index is 0 (no conclusion)")
        ok = False
    if not ok:
        return None
    found.mark(("rules", k), v.line, v.col)
    return Rule(combine("and" if conn == 1 else "or", props), tuple(then), weight)


def _method(sys: _Section, key: str, table: dict[str, str], found: Collector) -> str | None:
    v = sys.keys[key]
    word = _quoted(v, found, f"[System] {key}")
    if word is None:
        return None
    if word not in table:
        why = _WHY_NOT.get(
            word,
            f"{word!r} is not one of {', '.join(table)} (custom functions "
            "are refused, not approximated)",
        )
        found.add(v.line, v.col, f"[System] {key}: {why}")
        return None
    return table[word]


def loads(text: str, source: str = "<string>") -> RuleBase:
    """Parse the text of a file of this format (see :func:`loads_with_warnings`)."""
    return loads_with_warnings(text, source)[0]


def loads_with_warnings(text: str, source: str = "<string>") -> tuple[RuleBase, list[Problem]]:
    """Parse ``.fis`` text into a rule base; ``source`` names it in messages.

    Returns the rule base and the warnings (coverage gaps, located; see
    :func:`fuzzkit.formats.foreign_common.finish`).

    Raises
    ------
    RuleBaseError
        Every problem as ``source:line:col: message`` (malformed or truncated file, a rule
        referencing a missing term, a construct fuzzkit cannot express, a semantic problem).
    """
    found = Collector(source)
    sections = _split_sections(text, found)
    by_name = {s.name: s for s in sections}
    sys = by_name.get("System")
    if sys is None:
        found.add(1, 1, "missing [System] section (is this a .fis file?)")
        found.fail()
    for key, v in sys.keys.items():
        if key not in _SYSTEM_KEYS:
            found.add(v.line, 1, f"[System]: unknown key {key!r}")
    missing = [k for k in _SYSTEM_KEYS if k != "Version" and k not in sys.keys]
    if missing:
        found.add(sys.line, 1, f"[System]: missing {', '.join(missing)}")
        found.fail()
    name = _quoted(sys.keys["Name"], found, "[System] Name") or "imported"
    found.mark(("name",), sys.keys["Name"].line, sys.keys["Name"].col)
    found.mark((), sys.line, 1)  # problems of the whole rule base
    kind = _quoted(sys.keys["Type"], found, "[System] Type")
    if kind not in (None, "mamdani", "sugeno"):
        v = sys.keys["Type"]
        found.add(v.line, v.col, f"[System] Type: expected 'mamdani' or 'sugeno', got {kind!r}")
    sugeno = kind == "sugeno"
    counts = {
        k: _count(sys.keys[k], found, f"[System] {k}")
        for k in ("NumInputs", "NumOutputs", "NumRules")
    }
    and_ = _method(sys, "AndMethod", _AND, found)
    or_ = _method(sys, "OrMethod", _OR, found)
    imp = "min" if sugeno else _method(sys, "ImpMethod", _IMP, found)
    agg = "max" if sugeno else _method(sys, "AggMethod", _AGG, found)
    defuzz = _method(sys, "DefuzzMethod", _DEFUZZ, found)
    dv = sys.keys["DefuzzMethod"]
    if defuzz is not None and (defuzz in SUGENO_DEFUZZIFIERS) != sugeno:
        found.add(
            dv.line,
            dv.col,
            f"[System] DefuzzMethod: {dv.text} does not go with "
            f"Type='{kind}' (wtaver and wtsum are for Sugeno systems only)",
        )
    found.mark(("defuzzifier",), dv.line, dv.col)
    for key in ("AndMethod", "OrMethod", "ImpMethod", "AggMethod"):
        path_key = {
            "AndMethod": "and",
            "OrMethod": "or",
            "ImpMethod": "implication",
            "AggMethod": "aggregation",
        }[key]
        found.mark(("operators", path_key), sys.keys[key].line, sys.keys[key].col)
    n_in, n_out, n_rules = (counts[k] for k in ("NumInputs", "NumOutputs", "NumRules"))
    if n_in is None or n_out is None or n_rules is None:
        found.fail()
    groups: dict[str, list[Variable]] = {"input": [], "output": []}
    incomplete: dict[str, int] = {}  # variables whose MFs were not all read: their NumMFs
    for kind_, count in (("input", n_in), ("output", n_out)):
        title = kind_.capitalize()
        n_present = sum(1 for sec in sections if re.fullmatch(rf"{title}\d+", sec.name))
        for i in range(1, min(count, n_present + 1) + 1):
            sec = by_name.get(f"{title}{i}")
            if sec is None:
                declared = sys.keys[f"Num{title}s"]
                found.add(
                    declared.line,
                    declared.col,
                    f"Num{title}s={count} but [{title}{i}] is missing (truncated file?)",
                )
                continue
            var = _variable(sec, kind_, found, sugeno, n_in, incomplete)
            if var is not None:
                groups[kind_].append(var)
    for sec in sections:
        m = _SECTION.match(f"[{sec.name}]")
        base, num = (m.group(1), m.group(2)) if m else (sec.name, "")
        limit = {"Input": n_in, "Output": n_out}.get(base)
        known = base in ("System", "Rules") and not num
        if not known and (limit is None or not num or not 1 <= int(num) <= limit):
            found.add(sec.line, 1, f"unexpected section [{sec.name}]")
    rules_sec = by_name.get("Rules")
    if rules_sec is not None:
        found.mark(("rules",), rules_sec.line, 1)
    rules: list[Rule] = []
    if rules_sec is None:
        found.add(len(text.splitlines()) or 1, 1, "missing [Rules] section (truncated file?)")
    elif len(groups["input"]) == n_in and len(groups["output"]) == n_out:
        if len(rules_sec.rules) != n_rules:
            found.add(
                rules_sec.line,
                1,
                f"NumRules={n_rules} but [Rules] has "
                f"{len(rules_sec.rules)} rule lines (truncated file?)",
            )
        for k, v in enumerate(rules_sec.rules):
            rule = _rule(v, k, groups["input"], groups["output"], found, incomplete)
            if rule is not None:
                rules.append(rule)
    found.raise_if_any()
    rb = RuleBase(
        name=name,
        inputs=tuple(groups["input"]),
        outputs=tuple(groups["output"]),
        rules=tuple(rules),
        operators=Operators(and_ or "min", or_ or "max", imp or "min", agg or "max"),
        defuzzifier=defuzz or "centroid",
        out_of_range="extend",
    )
    return finish(rb, found, text)


def load(path: str | FsPath) -> RuleBase:
    """Read a ``.fis`` file (see :func:`loads`)."""
    return loads(read_text(path, "a .fis file"), str(path))


def load_with_warnings(path: str | FsPath) -> tuple[RuleBase, list[Problem]]:
    """:func:`load`, also returning the warnings (coverage gaps), located."""
    return loads_with_warnings(read_text(path, "a .fis file"), str(path))


# ---------------------------------------------------------------------------- export


def _mf_text(term: Term) -> str | None:
    written = shapes.write_term("fis", term.shape, term.params)
    if written is None:
        return None
    kind, params = written
    return f"'{term.name}':'{kind}',[{' '.join(fmt(x) for x in params)}]"


def refusals(rb: RuleBase) -> list[str]:
    """What in ``rb`` a ``.fis`` file cannot express at all (export is refused)."""
    out: list[str] = []
    sugeno = is_sugeno(rb)
    if rb.operators.aggregation not in _AGG.values() and not sugeno:
        out.append(
            f"aggregation {rb.operators.aggregation!r} (MATLAB has max, probor and an "
            "unbounded sum)"
        )
    if rb.defuzzifier not in _DEFUZZ.values():
        out.append(f"defuzzifier {rb.defuzzifier!r}")
    elif (rb.defuzzifier in SUGENO_DEFUZZIFIERS) != sugeno:
        out.append(
            f"defuzzifier {rb.defuzzifier!r} with "
            f"{'Sugeno' if sugeno else 'Mamdani'} terms (MATLAB's wtaver and wtsum are "
            "Sugeno only; fuzzkit's Mamdani weighted_average uses term centres)"
        )
    for var in rb.inputs + rb.outputs:
        for term in var.terms:
            if _mf_text(term) is None:
                out.append(f"term {var.name}.{term.name}: shape {term.shape!r}")
    for k, rule in enumerate(rb.rules):
        flat = flat_conditions(rule.antecedent)
        if flat is None:
            out.append(f"rule {k + 1}: nested and/or (a .fis rule is one AND or OR of conditions)")
        elif len({p.variable for p in flat[1]}) != len(flat[1]):
            out.append(f"rule {k + 1}: an input appears twice in one rule")
    return out


def losses(rb: RuleBase) -> list[str]:
    """What a ``.fis`` file would change in ``rb`` (export needs ``allow_loss=True``)."""
    out: list[str] = []
    if rb.out_of_range == "clamp":
        out.append(
            "out_of_range: clamp (MATLAB evaluates terms where the input is, so results "
            "differ outside the input ranges)"
        )
    for var in rb.outputs:
        mid = (var.low + var.high) / 2
        if var.default != mid:
            out.append(
                f"output {var.name!r}: default "
                f"{'NaN (none)' if var.default is None else fmt(var.default)} "
                f"(MATLAB gives the middle of the range, {fmt(mid)}, when no rule fires)"
            )
    if is_sugeno(rb) and (rb.operators.implication, rb.operators.aggregation) != ("min", "max"):
        out.append("implication/aggregation of a Sugeno system (MATLAB ignores them)")
    return out


def dumps(rb: RuleBase, *, allow_loss: bool = False) -> str:
    """The ``.fis`` text of ``rb``; ``loads(dumps(rb))`` equals ``rb`` up to its description.

    Raises
    ------
    ExportError
        ``rb`` holds something MATLAB cannot express (:func:`refusals`), or something a
        ``.fis`` would change (:func:`losses`) and ``allow_loss`` is false.
    """
    problems = refusals(rb)
    if problems:
        raise ExportError("fis", rb.name, problems)
    if not allow_loss and losses(rb):
        raise ExportError(
            "fis",
            rb.name,
            losses(rb),
            "pass allow_loss=True (--allow-loss) to export anyway, with MATLAB's meaning for these",
        )
    sugeno = is_sugeno(rb)
    rev_and = {v: k for k, v in _AND.items()}
    rev_or = {v: k for k, v in _OR.items()}
    rev_imp = {v: k for k, v in _IMP.items()}
    rev_agg = {v: k for k, v in _AGG.items()}
    rev_def = {v: k for k, v in _DEFUZZ.items()}
    lines = [
        "[System]",
        f"Name='{rb.name}'",
        f"Type='{'sugeno' if sugeno else 'mamdani'}'",
        "Version=2.0",
        f"NumInputs={len(rb.inputs)}",
        f"NumOutputs={len(rb.outputs)}",
        f"NumRules={len(rb.rules)}",
        f"AndMethod='{rev_and[rb.operators.and_]}'",
        f"OrMethod='{rev_or[rb.operators.or_]}'",
        f"ImpMethod='{'prod' if sugeno else rev_imp[rb.operators.implication]}'",
        f"AggMethod='{'sum' if sugeno else rev_agg[rb.operators.aggregation]}'",
        f"DefuzzMethod='{rev_def[rb.defuzzifier]}'",
    ]
    for title, group in (("Input", rb.inputs), ("Output", rb.outputs)):
        for i, var in enumerate(group, start=1):
            lines += [
                "",
                f"[{title}{i}]",
                f"Name='{var.name}'",
                f"Range=[{fmt(var.low)} {fmt(var.high)}]",
                f"NumMFs={len(var.terms)}",
            ]
            lines += [f"MF{j}={_mf_text(t)}" for j, t in enumerate(var.terms, start=1)]
    lines += ["", "[Rules]"]
    for rule in rb.rules:
        flat = flat_conditions(rule.antecedent)
        if flat is None:  # pragma: no cover - refused above
            raise AssertionError
        op, props = flat
        by_var = {p.variable: p for p in props}
        ant = []
        for var in rb.inputs:
            prop = by_var.get(var.name)
            idx = 0 if prop is None else var.term_index(prop.term) + 1
            ant.append(str(-idx if prop is not None and prop.negated else idx))
        then = {c.variable: c.term for c in rule.consequents}
        cons = [
            str(var.term_index(then[var.name]) + 1) if var.name in then else "0"
            for var in rb.outputs
        ]
        lines.append(
            f"{' '.join(ant)}, {' '.join(cons)} ({fmt(rule.weight)}) : {1 if op == 'and' else 2}"
        )
    return "\n".join(lines) + "\n"


def _write(rb: RuleBase, allow_loss: bool, dialect: str) -> str:
    return dumps(rb, allow_loss=allow_loss)


#: The format as :data:`fuzzkit.formats.registry.FORMATS` lists it.
FORMAT = ForeignFormat(
    name="fis",
    suffix=SUFFIX,
    label="MATLAB .fis",
    first_word="[System]",
    read=load_with_warnings,
    write=_write,
    losses=losses,
    meaning="MATLAB's",
)
