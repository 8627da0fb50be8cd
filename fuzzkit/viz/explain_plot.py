"""A figure of one point's inference (``fuzzkit eval --explain --png``), laid out as MATLAB's
rule viewer: one row per rule that fires (the strongest ``top``), one column per input and per
output. An input cell draws the term the rule tests, filled up to its membership at the point,
with the input value marked; an output cell draws the consequent term and, filled, the part
left after cutting (min) or scaling (product) it at the rule's firing strength, which is
written beside the row. The last row draws each input's whole partition with the value, and
each output's aggregated set with the defuzzified value. A Sugeno output draws each rule's
term value as a bar of its strength instead of a set."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from fuzzkit.fuzzy.describe import axis_label, num
from fuzzkit.fuzzy.explain import Explanation, OutputExplanation
from fuzzkit.fuzzy.membership import evaluate_term
from fuzzkit.fuzzy.model import RuleBase, Variable
from fuzzkit.fuzzy.rule_view import DEFAULT_RULES, RuleRow, rule_rows
from fuzzkit.viz.figures import new_figure, save_figure
from fuzzkit.viz.rulebase_plot import term_curve

_TERM = "0.55"  # the outline of a term
_INPUT_FILL = "#f2c14e"  # MATLAB's rule viewer fills memberships in yellow, outputs in blue
_OUTPUT_FILL = "tab:blue"
_VALUE = "tab:red"
_CELL_W = 2.1  # inches per column
_ROW_H = 0.52  # inches per rule row


def _curve(var: Variable, term: str, negated: bool = False) -> tuple[Any, Any]:
    """The term's curve over the range, sampled densely enough to cut it at any level."""
    k = var.term_index(term)
    x, _ = term_curve(var, k)
    x = np.unique(np.concatenate([x, np.linspace(var.low, var.high, 401)]))
    mu = evaluate_term(var.terms[k], x)
    return x, (1.0 - mu if negated else mu)


def _input_cell(ax: Any, var: Variable, row: RuleRow, seen: float) -> None:
    cells = row.inputs.get(var.name, ())
    labels = []
    for cell in cells:
        x, mu = _curve(var, cell.term, cell.negated)
        ax.fill_between(x, np.minimum(mu, cell.truth), color=_INPUT_FILL, lw=0)
        ax.plot(x, mu, color=_TERM, lw=0.9)
        labels.append(f"{'not ' if cell.negated else ''}{cell.term} {cell.truth:.2f}")
    if labels:
        ax.text(0.02, 0.93, ", ".join(labels), transform=ax.transAxes, va="top", fontsize=7)
    else:
        ax.text(
            0.5, 0.5, "not tested", transform=ax.transAxes, ha="center", va="center",
            fontsize=7, color="0.6",
        )  # fmt: skip
    ax.axvline(seen, color=_VALUE, lw=1.0)


def _output_cell(
    ax: Any, rb: RuleBase, var: Variable, out: OutputExplanation, row: RuleRow
) -> None:
    cell = row.outputs.get(var.name)
    if cell is None:
        return
    label = cell.term
    if var.is_sugeno:
        z = out.term_values[cell.term]
        ax.vlines(z, 0.0, cell.level, color=_OUTPUT_FILL, lw=2.5)
        label += f" = {num(z)}"
    else:
        x, mu = _curve(var, cell.term)
        cut = np.minimum(mu, cell.level) if rb.operators.implication == "min" else mu * cell.level
        ax.fill_between(x, cut, color=_OUTPUT_FILL, alpha=0.6, lw=0)
        ax.plot(x, mu, color=_TERM, lw=0.9)
    ax.text(0.02, 0.93, label, transform=ax.transAxes, va="top", fontsize=7)


def _aggregate_cell(ax: Any, var: Variable, out: OutputExplanation) -> None:
    if len(out.y):
        for k in range(len(var.terms)):
            x, mu = term_curve(var, k)
            ax.plot(x, mu, color="0.8", lw=0.7)
        if out.mu_lower is None:
            ax.fill_between(out.y, out.mu, color=_OUTPUT_FILL, alpha=0.6, lw=0)
        else:  # interval type-2: the footprint between the lower and the upper set
            ax.fill_between(out.y, out.mu_lower, out.mu, color=_OUTPUT_FILL, alpha=0.3, lw=0)
            ax.fill_between(out.y, out.mu_lower, color=_OUTPUT_FILL, alpha=0.6, lw=0)
            ax.plot(out.y, out.mu_lower, color=_OUTPUT_FILL, lw=1.0, ls="--")
        ax.plot(out.y, out.mu, color=_OUTPUT_FILL, lw=1.0)
    else:
        for name, z in out.term_values.items():
            ax.vlines(z, 0.0, out.activations[name], color=_OUTPUT_FILL, lw=2.5)
    ax.axvline(out.value, color=_VALUE, lw=2.0)
    label = f"{out.name} = {num(out.value)}\n{out.defuzzifier}"
    if out.interval is not None:
        for end in out.interval:
            ax.axvline(end, color=_VALUE, lw=1.0, ls=":")
        label += f"\n[{num(out.interval[0])}, {num(out.interval[1])}]"
    ax.text(
        0.98, 0.97, label, transform=ax.transAxes,
        ha="right", va="top", fontsize=7, color=_VALUE,
        bbox={"facecolor": "white", "edgecolor": "none", "alpha": 0.8, "pad": 1.0},
    )  # fmt: skip


#: Term labels of the last row: font size (points), and the width of one character as a
#: fraction of it (a generous mean for DejaVu Sans, so that estimated labels never touch).
_LABEL_PT = 6.0
_CHAR_EM = 0.65


def term_label_layout(
    peaks: list[float], names: list[str], low: float, high: float, per_char: float
) -> list[tuple[str, float, str, int]]:
    """Where each term's label goes above the partition: ``(name, x, ha, level)``.

    ``per_char`` is one character's width in data units. A label is centred on its term's
    peak, kept inside ``[low, high]`` (a label at an end is aligned to that end, so it is not
    clipped nor drawn over the next column), and raised one level when it would overlap the
    label before it on its level (narrow terms side by side), so that no two labels overlap.
    """
    out: list[tuple[str, float, str, int]] = []
    right_end: dict[int, float] = {}  # the rightmost extent used on each level
    for peak, name in sorted(zip(peaks, names, strict=True)):
        width = per_char * len(name)
        left = min(max(peak - width / 2, low), high - width)
        ha = "left" if left <= low else ("right" if left >= high - width else "center")
        x = {"left": low, "right": high, "center": peak}[ha]
        level = 0
        while right_end.get(level, -np.inf) > left - 0.3 * per_char:
            level += 1
        right_end[level] = left + width
        out.append((name, x, ha, level))
    return out


def _partition_cell(ax: Any, var: Variable, seen: float) -> None:
    peaks, names = [], []
    for k, term in enumerate(var.terms):
        x, mu = term_curve(var, k)
        ax.plot(x, mu, color=_TERM, lw=0.7)
        peaks.append(float(x[int(np.argmax(mu))]))
        names.append(term.name)
    width_in = ax.get_position().width * ax.figure.get_figwidth()
    per_char = (var.high - var.low) / width_in * _LABEL_PT * _CHAR_EM / 72.0
    for name, x, ha, level in term_label_layout(peaks, names, var.low, var.high, per_char):
        ax.text(x, 1.02 + 0.2 * level, name, ha=ha, va="bottom", fontsize=_LABEL_PT)
    ax.axvline(seen, color=_VALUE, lw=1.5)


def _strength(explanation: Explanation, row: RuleRow) -> str:
    """The firing strength beside a rule's row: ``w [lower, upper]`` for an IT2 rule."""
    lower = next((r.lower for r in explanation.rules if r.index == row.index), None)
    if lower is None:
        return f"w {row.strength:.3f}"
    return f"w [{lower:.3f},\n   {row.strength:.3f}]"


def explanation_figure(rb: RuleBase, explanation: Explanation, top: int = DEFAULT_RULES) -> Any:
    """The rule-view figure (matplotlib, no pyplot) of ``explanation``, ``top`` rules at most."""
    rows = rule_rows(rb, explanation, top)
    inputs = [rb.input(i.name) for i in explanation.inputs]
    outputs = [rb.output(o.name) for o in explanation.outputs]
    n_rows, n_cols = len(rows) + 1, len(inputs) + len(outputs)
    fig = new_figure(_CELL_W * n_cols + 1.9, _ROW_H * len(rows) + 2.3)
    grid = fig.add_gridspec(
        n_rows,
        n_cols,
        height_ratios=[1.0] * len(rows) + [1.9],
        left=1.05 / (_CELL_W * n_cols + 1.9),
        right=1.0 - 0.85 / (_CELL_W * n_cols + 1.9),
        top=1.0 - 0.75 / (_ROW_H * len(rows) + 2.3),
        bottom=0.45 / (_ROW_H * len(rows) + 2.3),
        hspace=0.12 if rows else 0.0,
        wspace=0.16,
    )
    for c, var in enumerate([*inputs, *outputs]):
        first = None
        for r in range(n_rows):
            ax = fig.add_subplot(grid[r, c], sharex=first)
            first = first or ax
            ax.set_xlim(var.low, var.high)
            ax.set_ylim(0.0, 1.15 if r < n_rows - 1 else 1.45)
            ax.set_yticks([])
            if r < n_rows - 1:
                ax.tick_params(labelbottom=False, length=0)
            else:
                ax.tick_params(labelsize=7)
                ax.set_xlabel(axis_label(var), fontsize=8)
            if c < len(inputs):
                inp = explanation.inputs[c]
                if r == 0:
                    head = f"{inp.name} = {num(inp.value)}"
                    if inp.seen != inp.value:
                        head += f" (seen {num(inp.seen)})"
                    ax.set_title(head, fontsize=9, pad=4)
                if r < len(rows):
                    _input_cell(ax, var, rows[r], inp.seen)
                else:
                    _partition_cell(ax, var, inp.seen)
            else:
                out = explanation.outputs[c - len(inputs)]
                if r < len(rows):
                    if r == 0:
                        ax.set_title(out.name, fontsize=9, pad=4)
                    _output_cell(ax, rb, var, out, rows[r])
                else:
                    _aggregate_cell(ax, var, out)
            if c == 0 and r < len(rows):
                ax.set_ylabel(
                    f"rule {rows[r].index}", rotation=0, ha="right", va="center", fontsize=8
                )
            if c == n_cols - 1 and r < len(rows):
                ax.text(
                    1.04, 0.5, _strength(explanation, rows[r]), transform=ax.transAxes,
                    va="center", fontsize=8,
                )  # fmt: skip
            if c == 0 and r == n_rows - 1:
                ax.set_ylabel("all", rotation=0, ha="right", va="center", fontsize=8)
    fired = len(explanation.rules)
    shown = f"all {fired} drawn" if len(rows) == fired else f"the {len(rows)} strongest drawn"
    point = ", ".join(f"{i.name} = {num(i.value)}" for i in explanation.inputs)
    ops = rb.operators
    key = (
        "w: firing interval [lower, upper]; shaded: the footprint, dotted: [y_l, y_r]"
        if any(o.interval is not None for o in explanation.outputs)
        else "w: firing strength"
    )
    fig.suptitle(
        f"{explanation.rulebase} at {point}: {fired} of {len(rb.rules)} rules fire ({shown})\n"
        f"and = {ops.and_}, implication = {ops.implication}, aggregation = {ops.aggregation}; "
        + key,
        fontsize=9,
    )
    return fig


def write_explanation_png(
    rb: RuleBase,
    explanation: Explanation,
    path: str | os.PathLike[str],
    top: int = DEFAULT_RULES,
) -> Path:
    """Write :func:`explanation_figure` to ``path`` (.png or .svg), atomically."""
    return save_figure(explanation_figure(rb, explanation, top), path, dpi=130)
