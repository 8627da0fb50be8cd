"""A rule base as people read it: labels with units, the rule table, rules as sentences.

Shared by ``fuzzkit info``, the figures (:mod:`fuzzkit.viz.rulebase_plot`) and the notebook
display of a :class:`~fuzzkit.fuzzy.model.RuleBase` (``_repr_markdown_`` / ``_repr_html_``,
registered with :mod:`fuzzkit.fuzzy.display` on import), so that all of them say the same thing.
Formats from the model's fields only.
"""

from __future__ import annotations

import html
import math
from dataclasses import dataclass

from fuzzkit.fuzzy.display import register_renderer
from fuzzkit.fuzzy.model import Compound, Expression, Proposition, Rule, RuleBase, Variable

#: What an empty cell of a rule table shows (as in the YAML format).
EMPTY_CELL = "-"


def num(x: float) -> str:
    """A number as the descriptions show it: 6 significant digits, no trailing zeros."""
    return f"{x:.6g}"


#: An output within this many units in the last place of its range's scale of zero is shown
#: as 0: the rounding noise of a centroid that is 0 by symmetry (``-1.7e-15``), not a value.
#: 64 ulps is the tolerance the golden files allow the generated code (docs/development.md);
#: the exact engine's own accuracy claim, 1e-9 of the range, is far coarser.
ZERO_ULPS = 64


def shown_output(value: float, var: Variable) -> float:
    """``value`` of the output ``var`` as ``eval`` and the rule view show it: exactly 0.0 when
    ``|value| <= ZERO_ULPS * ulp(max(|low|, |high|))``, else unchanged (NaN included).

    Examples
    --------
    For a range [-1, 1] the threshold is 64 * 2.2e-16 = 1.4e-14: ``-1.67e-15`` is shown as
    0.0, ``1e-13`` as itself.
    """
    scale = max(abs(var.low), abs(var.high))
    return 0.0 if abs(value) <= ZERO_ULPS * math.ulp(scale) else value


def axis_label(var: Variable) -> str:
    """A variable's name with its units for an axis or a column head: ``e [N]`` or ``e``."""
    return f"{var.name} [{var.units}]" if var.units else var.name


def range_text(var: Variable) -> str:
    """``[-20, 20] K``: the universe of a variable with its units."""
    text = f"[{num(var.low)}, {num(var.high)}]"
    return f"{text} {var.units}" if var.units else text


def format_expression(expr: Expression, top: bool = True) -> str:
    """A condition as text: ``e is PS and (de is NS or de is not ZR)``."""
    if isinstance(expr, Proposition):
        return f"{expr.variable} is {'not ' if expr.negated else ''}{expr.term}"
    text = f" {expr.op} ".join(format_expression(o, top=False) for o in expr.operands)
    return text if top else f"({text})"


def rule_sentence(rule: Rule) -> str:
    """One rule as ``if e is PS and de is NS then du is ZR (weight 0.5)``."""
    then = " and ".join(f"{c.variable} is {c.term}" for c in rule.consequents)
    weight = f"  (weight {num(rule.weight)})" if rule.weight != 1.0 else ""
    return f"if {format_expression(rule.antecedent)} then {then}{weight}"


@dataclass(frozen=True)
class RuleGrid:
    """A rule table as a grid: ``cells[i][j]`` is the output label for ``rows[i]``, ``columns[j]``.

    Rows keep the order the table was written in (the paper prints PL at the top); empty cells
    hold :data:`EMPTY_CELL`.
    """

    row_input: str
    column_input: str
    output: str
    rows: tuple[str, ...]
    columns: tuple[str, ...]
    cells: tuple[tuple[str, ...], ...]


def rule_grid(rb: RuleBase) -> RuleGrid | None:
    """The rules as a table: written as one, or a list that is one (:func:`full_grid`, as a
    ``.fis`` file writes a table); ``None`` otherwise."""
    t = rb.table
    if t is None:
        return full_grid(rb)
    try:
        rows, cols = rb.input(t.rows).term_names, rb.input(t.columns).term_names
    except KeyError:
        return None
    cell: dict[tuple[str, str], str] = {}
    row_order: list[str] = []
    for rule in rb.rules:
        a = rule.antecedent
        if not (isinstance(a, Compound) and len(a.operands) == 2):
            return None
        rp, cp = a.operands
        if not (isinstance(rp, Proposition) and isinstance(cp, Proposition)):
            return None
        cell[rp.term, cp.term] = rule.consequents[0].term
        row_order.append(rp.term)
    rows_shown = tuple(dict.fromkeys(row_order + list(rows)))
    return RuleGrid(
        row_input=t.rows,
        column_input=t.columns,
        output=t.output,
        rows=rows_shown,
        columns=tuple(cols),
        cells=tuple(tuple(cell.get((r, c), EMPTY_CELL) for c in cols) for r in rows_shown),
    )


def full_grid(rb: RuleBase) -> RuleGrid | None:
    """List-form rules that are a complete table, as that table; else ``None``.

    They are when the rule base has two inputs and one output, and its rules are exactly one
    ``if A is a and B is b then out is c`` (weight 1, nothing negated) for every pair of terms
    ``(a, b)``: what a table means, so showing them as one loses nothing. Rows and columns
    keep the terms' order.
    """
    if len(rb.inputs) != 2 or len(rb.outputs) != 1:
        return None
    first, second = rb.inputs
    cell: dict[tuple[str, str], str] = {}
    for rule in rb.rules:
        a = rule.antecedent
        if rule.weight != 1.0 or len(rule.consequents) != 1:
            return None
        if not (isinstance(a, Compound) and a.op == "and" and len(a.operands) == 2):
            return None
        props = [p for p in a.operands if isinstance(p, Proposition) and not p.negated]
        by_var = {p.variable: p.term for p in props}
        if len(props) != 2 or set(by_var) != {first.name, second.name}:
            return None
        key = (by_var[first.name], by_var[second.name])
        if key in cell:
            return None
        cell[key] = rule.consequents[0].term
    rows, cols = first.term_names, second.term_names
    if len(cell) != len(rows) * len(cols):
        return None
    return RuleGrid(
        row_input=first.name,
        column_input=second.name,
        output=rb.outputs[0].name,
        rows=tuple(rows),
        columns=tuple(cols),
        cells=tuple(tuple(cell[r, c] for c in cols) for r in rows),
    )


def _term_summary(var: Variable) -> str:
    return " ".join(t.name for t in var.terms)


def _operators_text(rb: RuleBase) -> str:
    ops = rb.operators
    return (
        f"and={ops.and_}, or={ops.or_}, implication={ops.implication}, "
        f"aggregation={ops.aggregation}; defuzzifier {rb.defuzzifier}; "
        f"out of range: {rb.out_of_range}"
    )


def _md_escape(text: str) -> str:
    return text.replace("\\", "\\\\").replace("|", "\\|").replace("*", "\\*").replace("_", "\\_")


def to_markdown(rb: RuleBase) -> str:
    """The rule base as Markdown (what a notebook shows for ``_repr_markdown_``)."""
    e = _md_escape
    lines = [f"**Rule base `{rb.name}`**" + (f": {e(rb.description)}" if rb.description else "")]
    lines += ["", "| | variable | range | units | terms |", "|---|---|---|---|---|"]
    for kind, group in (("input", rb.inputs), ("output", rb.outputs)):
        for var in group:
            lines.append(
                f"| {kind} | `{var.name}` | [{num(var.low)}, {num(var.high)}] | "
                f"{e(var.units or '')} | {_term_summary(var)} |"
            )
    lines += ["", f"Operators: {_operators_text(rb)}.", ""]
    grid = rule_grid(rb)
    if grid is not None:
        lines.append(
            f"Rules ({len(rb.rules)}): table of `{grid.output}`, rows `{grid.row_input}`, "
            f"columns `{grid.column_input}`"
        )
        lines.append("")
        lines.append(
            f"| {grid.row_input} \\\\ {grid.column_input} | " + " | ".join(grid.columns) + " |"
        )
        lines.append("|---" * (len(grid.columns) + 1) + "|")
        for r, row in zip(grid.rows, grid.cells, strict=True):
            lines.append(f"| **{r}** | " + " | ".join(row) + " |")
    else:
        lines.append(f"Rules ({len(rb.rules)}):")
        lines.append("")
        lines += [f"{k}. {e(rule_sentence(rule))}" for k, rule in enumerate(rb.rules, 1)]
    return "\n".join(lines) + "\n"


def to_html(rb: RuleBase) -> str:
    """The rule base as an HTML fragment (what a notebook shows for ``_repr_html_``)."""
    h = html.escape
    parts = [
        '<div class="fuzzkit-rulebase">',
        f"<p><b>Rule base <code>{h(rb.name)}</code></b>"
        + (f": {h(rb.description)}" if rb.description else "")
        + "</p>",
        "<table><thead><tr><th></th><th>variable</th><th>range</th><th>units</th>"
        "<th>terms</th></tr></thead><tbody>",
    ]
    for kind, group in (("input", rb.inputs), ("output", rb.outputs)):
        for var in group:
            parts.append(
                f"<tr><td>{kind}</td><td><code>{h(var.name)}</code></td>"
                f"<td>[{num(var.low)}, {num(var.high)}]</td><td>{h(var.units or '')}</td>"
                f"<td>{h(_term_summary(var))}</td></tr>"
            )
    parts.append("</tbody></table>")
    parts.append(f"<p>Operators: {h(_operators_text(rb))}.</p>")
    grid = rule_grid(rb)
    if grid is not None:
        parts.append(
            f"<p>Rules ({len(rb.rules)}): table of <code>{h(grid.output)}</code>, rows "
            f"<code>{h(grid.row_input)}</code>, columns <code>{h(grid.column_input)}</code></p>"
        )
        head = "".join(f"<th>{h(c)}</th>" for c in grid.columns)
        parts.append(
            f"<table><thead><tr><th>{h(grid.row_input)} \\ {h(grid.column_input)}</th>"
            f"{head}</tr></thead><tbody>"
        )
        for r, row in zip(grid.rows, grid.cells, strict=True):
            cells = "".join(f"<td>{h(c)}</td>" for c in row)
            parts.append(f"<tr><th>{h(r)}</th>{cells}</tr>")
        parts.append("</tbody></table>")
    else:
        parts.append(f"<p>Rules ({len(rb.rules)}):</p><ol>")
        parts += [f"<li>{h(rule_sentence(rule))}</li>" for rule in rb.rules]
        parts.append("</ol>")
    parts.append("</div>")
    return "\n".join(parts)


register_renderer("markdown", to_markdown)
register_renderer("html", to_html)
