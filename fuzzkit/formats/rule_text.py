"""Textual rules, ``if e is NS and de is not PS then du is ZR with 0.5``, read and written.

FLL (lower-case keywords) and FCL (keywords in any case, ``RULE n :`` prefix and ``;`` handled
by the FCL reader) share this grammar::

    rule       := IF condition THEN conclusion {AND conclusion} [WITH number]
    condition  := part {AND part} | part {OR part}     (mixing AND and OR needs parentheses)
    part       := '(' condition ')' | [NOT] variable IS [NOT] term
    conclusion := variable IS term

Hedges (``very``, ``somewhat``, ``seldom``, ``extremely``, ``any``), ``NOT`` before a
parenthesis and mixed AND/OR without parentheses are refused with their column: fuzzkit cannot
express the first two, and the third reads differently in different tools.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass

from fuzzkit.formats.foreign_common import Collector, combine, fmt, parse_number
from fuzzkit.fuzzy.model import (
    Compound,
    Consequent,
    Expression,
    Proposition,
    Rule,
    Variable,
)
from fuzzkit.fuzzy.validation import MAX_CONDITION_DEPTH

#: Parentheses nest at most this deep (a hostile file must not exhaust the stack); a
#: condition of the most and/or levels validation allows needs one level fewer.
MAX_DEPTH = MAX_CONDITION_DEPTH
HEDGES = frozenset({"very", "somewhat", "seldom", "extremely", "any"})
_TOKEN = re.compile(r"\(|\)|[^\s()]+")


@dataclass(frozen=True)
class _Tok:
    text: str
    col: int


class _Fail(Exception):
    pass


class _Parser:
    def __init__(
        self,
        text: str,
        line: int,
        col0: int,
        inputs: dict[str, Variable],
        outputs: dict[str, Variable],
        found: Collector,
    ) -> None:
        self.toks = [_Tok(m.group(), col0 + m.start()) for m in _TOKEN.finditer(text)]
        self.i = 0
        self.depth = 0
        self.line = line
        self.end_col = col0 + len(text)
        self.inputs, self.outputs, self.found = inputs, outputs, found

    def fail(self, tok: _Tok | None, message: str) -> _Fail:
        self.found.add(self.line, tok.col if tok else self.end_col, message)
        return _Fail()

    def peek(self) -> _Tok | None:
        return self.toks[self.i] if self.i < len(self.toks) else None

    def word(self) -> str:
        tok = self.peek()
        return tok.text.lower() if tok else ""

    def take(self, what: str = "more") -> _Tok:
        """The next token, whatever it is (``what`` says what was expected if there is none)."""
        tok = self.peek()
        if tok is None:
            raise self.fail(None, f"rule ends early (expected {what})")
        self.i += 1
        return tok

    def expect(self, keyword: str) -> _Tok:
        """The next token, which must be ``keyword`` (in any case)."""
        tok = self.take(repr(keyword))
        if tok.text.lower() != keyword:
            raise self.fail(tok, f"expected {keyword!r}, got {tok.text!r}")
        return tok

    def condition(self) -> Expression:
        parts = [self.part()]
        op = ""
        while self.word() in ("and", "or"):
            tok = self.take()
            if op and tok.text.lower() != op:
                raise self.fail(
                    tok,
                    "mixing 'and' and 'or' without parentheses is ambiguous "
                    "(tools disagree on precedence); add parentheses",
                )
            op = tok.text.lower()
            parts.append(self.part())
        if not op:
            return parts[0]
        # a nested compound with the same connective is the same condition, flattened
        flat: list[Expression] = []
        for p in parts:
            flat.extend(p.operands if isinstance(p, Compound) and p.op == op else [p])
        return combine(op, flat)

    def part(self) -> Expression:
        tok = self.peek()
        if tok is not None and tok.text == "(":
            self.take()
            self.depth += 1
            if self.depth > MAX_DEPTH:
                raise self.fail(tok, f"parentheses nested deeper than {MAX_DEPTH}")
            inner = self.condition()
            self.depth -= 1
            self.expect(")")
            return inner
        negated = False
        if self.word() == "not":
            not_tok = self.take()
            nxt = self.peek()
            if nxt is not None and nxt.text == "(":
                raise self.fail(
                    not_tok,
                    "'not' before a parenthesis (a negated compound) "
                    "cannot be expressed in fuzzkit",
                )
            negated = True
        var_tok = self.take("a variable name")
        self.expect("is")
        if self.word() == "not":
            self.take()
            negated = not negated
        term_tok = self.take("a term name")
        if term_tok.text.lower() in HEDGES:
            raise self.fail(
                term_tok,
                f"hedge {term_tok.text!r} cannot be expressed in fuzzkit "
                "(refused, not approximated)",
            )
        var = self.lookup(var_tok, self.inputs, "input")
        self.check_term(var, term_tok, "input")
        return Proposition(var.name, term_tok.text, negated)

    def lookup(self, tok: _Tok, pool: dict[str, Variable], kind: str) -> Variable:
        var = pool.get(tok.text)
        if var is None:
            other = self.outputs if kind == "input" else self.inputs
            if tok.text in other:
                raise self.fail(
                    tok,
                    f"{tok.text!r} is an {'output' if kind == 'input' else 'input'}"
                    f"; expected an {kind} here",
                )
            raise self.fail(
                tok, f"unknown {kind} {tok.text!r}; expected one of {', '.join(pool) or '(none)'}"
            )
        return var

    def check_term(self, var: Variable, tok: _Tok, kind: str) -> None:
        if tok.text not in var.term_names:
            raise self.fail(
                tok,
                f"unknown term {tok.text!r} of {kind} {var.name!r}; expected "
                f"one of {', '.join(var.term_names) or '(none)'}",
            )

    def conclusion(self) -> list[Consequent]:
        out = [self.one_conclusion()]
        while self.word() == "and":
            self.take()
            out.append(self.one_conclusion())
        return out

    def one_conclusion(self) -> Consequent:
        var_tok = self.take("an output name")
        self.expect("is")
        term_tok = self.take("a term name")
        if term_tok.text.lower() in HEDGES | {"not"}:
            raise self.fail(
                term_tok,
                f"{term_tok.text!r} in a conclusion cannot be expressed in "
                "fuzzkit (refused, not approximated)",
            )
        var = self.lookup(var_tok, self.outputs, "output")
        self.check_term(var, term_tok, "output")
        return Consequent(var.name, term_tok.text)

    def rule(self) -> Rule:
        self.expect("if")
        cond = self.condition()
        self.expect("then")
        then = self.conclusion()
        weight = 1.0
        if self.word() == "with":
            self.take()
            wtok = self.take("a weight")
            w = parse_number(wtok.text)
            if w is None:
                raise self.fail(wtok, f"expected a number after 'with', got {wtok.text!r}")
            weight = w
        extra = self.peek()
        if extra is not None:
            raise self.fail(extra, f"unexpected {extra.text!r} after the rule")
        return Rule(cond, tuple(then), weight)


def parse_rule(
    text: str,
    line: int,
    col: int,
    inputs: dict[str, Variable],
    outputs: dict[str, Variable],
    found: Collector,
) -> Rule | None:
    """One textual rule (starting at ``line``:``col``), or None after adding its problem."""
    try:
        return _Parser(text, line, col, inputs, outputs, found).rule()
    except _Fail:
        return None


def _expression(expr: Expression, key: Callable[[str], str], top: bool) -> str:
    if isinstance(expr, Proposition):
        neg = f"{key('not')} " if expr.negated else ""
        return f"{expr.variable} {key('is')} {neg}{expr.term}"
    inner = f" {key(expr.op)} ".join(_expression(e, key, False) for e in expr.operands)
    return inner if top else f"({inner})"


def rule_text(rule: Rule, upper: bool = False) -> str:
    """``rule`` in this grammar (keywords upper-case for FCL); nested compounds parenthesised."""

    def key(word: str) -> str:
        return word.upper() if upper else word

    then = f" {key('and')} ".join(f"{c.variable} {key('is')} {c.term}" for c in rule.consequents)
    text = f"{key('if')} {_expression(rule.antecedent, key, True)} {key('then')} {then}"
    if rule.weight != 1.0:
        text += f" {key('with')} {fmt(rule.weight)}"
    return text


def variables(rb_inputs: tuple[Variable, ...]) -> dict[str, Variable]:
    """Variables by name, for :func:`parse_rule`."""
    return {v.name: v for v in rb_inputs}
