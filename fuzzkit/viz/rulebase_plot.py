"""One figure of a whole rule base: every variable's membership functions and the rules.

The left column plots the terms of each input, then each output, over the variable's range
(like MATLAB's ``plotmf``), with units on the axis; an interval type-2 term is drawn as its
upper (solid) and lower (dashed) functions with the footprint of uncertainty between them
shaded; the right panel shows the rules: a coloured
grid for a rule table (rows and columns are the two inputs' labels, each cell the output label),
or the rules as numbered sentences for list-form rules (what ``fuzzkit info`` prints).
"""

from __future__ import annotations

import os
import textwrap
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib import colormaps

from fuzzkit.fuzzy.describe import (
    EMPTY_CELL,
    RuleGrid,
    axis_label,
    rule_grid,
    rule_sentence,
)
from fuzzkit.fuzzy.membership import breakpoints, evaluate_term
from fuzzkit.fuzzy.model import RuleBase, Variable
from fuzzkit.fuzzy.shapes import shape
from fuzzkit.fuzzy.type2_model import Footprint, LowerTerm, footprint_of
from fuzzkit.viz.figures import figure_format, new_figure, save_figure

#: Height of one membership-function panel (inches).
PANEL_HEIGHT = 1.75
#: Characters per line of a rule sentence before it wraps.
RULE_WRAP = 66
#: Points per variable range at which smooth shapes are sampled.
SAMPLES = 801


def term_curve(var: Variable, index: int) -> tuple[Any, Any]:
    """``x`` over the range and ``mu(x)``: a piecewise-linear term exactly, by its corners (a
    few points, so SVGs stay small), a smooth one sampled at :data:`SAMPLES` points."""
    term = var.terms[index]
    if term.is_piecewise_linear:
        corners = [p for p in breakpoints(term) if var.low < p < var.high]
        x = np.unique(np.array([var.low, *corners, var.high], dtype=np.float64))
    else:
        x = np.linspace(var.low, var.high, SAMPLES)
    return x, evaluate_term(term, x)


def _peak(x: Any, mu: Any) -> float:
    """Middle of where ``mu`` is largest (a plateau's centre), for placing the label."""
    top = x[mu >= np.nanmax(mu) - 1e-9]
    return float(0.5 * (top[0] + top[-1]))


def footprint_curves(var: Variable, index: int, lower: LowerTerm) -> tuple[Any, Any, Any]:
    """``x``, the upper and the lower membership of an interval type-2 term: exactly at both
    shapes' corners when both are piecewise linear, else sampled at :data:`SAMPLES` points."""
    term = var.terms[index]
    if term.is_piecewise_linear and lower.shape.is_piecewise_linear:
        corners = [p for t in (term, lower.shape) for p in breakpoints(t) if var.low < p < var.high]
        x = np.unique(np.array([var.low, *corners, var.high], dtype=np.float64))
    else:
        x = np.linspace(var.low, var.high, SAMPLES)
    return x, evaluate_term(term, x), lower.scale * evaluate_term(lower.shape, x)


def _plot_variable(ax: Any, var: Variable, kind: str, footprint: Footprint | None = None) -> None:
    colours = [colormaps["tab10"](i % 10) for i in range(len(var.terms))]
    for k, term in enumerate(var.terms):
        colour = colours[k]
        lower = footprint.lower(var.name, term.name) if footprint is not None else None
        if lower is not None:  # interval type-2: the footprint of uncertainty shaded
            x, mu, mu_lower = footprint_curves(var, k, lower)
            ax.plot(x, mu, color=colour, lw=1.6)
            ax.plot(x, mu_lower, color=colour, lw=1.1, ls="--")
            ax.fill_between(x, mu_lower, mu, color=colour, alpha=0.28, lw=0)
            at = _peak(x, mu)
        elif shape(term.shape).impulse:  # no area: a spike at its value
            value = term.params[0]
            ax.vlines(value, 0.0, 1.0, color=colour, lw=2)
            ax.plot([value], [1.0], "o", color=colour, ms=4)
            at = value
        else:
            x, mu = term_curve(var, k)
            ax.plot(x, mu, color=colour, lw=1.6)
            ax.fill_between(x, mu, color=colour, alpha=0.08, lw=0)
            at = _peak(x, mu)
        # A label at a range end would stick out of the panel: align it inwards there.
        edge = 0.04 * (var.high - var.low)
        ha = "left" if at < var.low + edge else "right" if at > var.high - edge else "center"
        ax.text(at, 1.04, term.name, color=colour, ha=ha, va="bottom", fontsize=8)
    ax.set_xlim(var.low, var.high)
    ax.set_ylim(0.0, 1.22)
    ax.set_yticks([0.0, 0.5, 1.0])
    ax.set_ylabel("membership", fontsize=8)
    ax.set_xlabel(f"{kind} {axis_label(var)}", fontsize=9, labelpad=1)
    ax.tick_params(labelsize=8)
    ax.grid(alpha=0.25)


def _plot_table(ax: Any, rb: RuleBase, grid: RuleGrid) -> None:
    out = rb.output(grid.output)
    labels = list(out.term_names)
    index = np.array(
        [[labels.index(c) if c in labels else np.nan for c in row] for row in grid.cells]
    )
    cmap = colormaps["coolwarm"].with_extremes(bad="white")
    ax.imshow(
        np.ma.masked_invalid(index),
        cmap=cmap,
        vmin=0,
        vmax=max(len(labels) - 1, 1),
        aspect="auto",
        alpha=0.75,
    )
    size = 9 if max(len(grid.rows), len(grid.columns)) <= 7 else 7
    for i, row in enumerate(grid.cells):
        for j, cell in enumerate(row):
            ax.text(j, i, cell, ha="center", va="center", fontsize=size)
    ax.set_xticks(range(len(grid.columns)), grid.columns, fontsize=8)
    ax.set_yticks(range(len(grid.rows)), grid.rows, fontsize=8)
    ax.xaxis.tick_top()
    ax.xaxis.set_label_position("top")
    ax.set_xlabel(f"columns: {axis_label(rb.input(grid.column_input))}", fontsize=9)
    ax.set_ylabel(f"rows: {axis_label(rb.input(grid.row_input))}", fontsize=9)
    ax.set_xticks(np.arange(len(grid.columns) + 1) - 0.5, minor=True)
    ax.set_yticks(np.arange(len(grid.rows) + 1) - 0.5, minor=True)
    ax.grid(which="minor", color="white", lw=1.5)
    ax.tick_params(which="minor", length=0)
    empty = sum(c == EMPTY_CELL for row in grid.cells for c in row)
    note = f"; {empty} empty cells ({EMPTY_CELL})" if empty else ""
    ax.set_title(
        f"rules: {len(rb.rules)} as a table of {axis_label(out)}{note}",
        fontsize=10,
        y=-0.08,
        va="top",
    )


def _plot_rule_list(ax: Any, rb: RuleBase, lines_fit: int) -> None:
    ax.axis("off")
    width = len(str(len(rb.rules)))
    lines: list[str] = []
    for k, rule in enumerate(rb.rules, start=1):
        # A no-break space keeps "(weight 0.5)" on one line (textwrap splits ASCII blanks only).
        sentence = rule_sentence(rule).replace("(weight ", "(weight\u00a0")
        wrapped = textwrap.wrap(sentence, RULE_WRAP, subsequent_indent=" " * (width + 2))
        lines += [f"{str(k).rjust(width)}. {wrapped[0]}", *wrapped[1:]]
    if len(lines) > lines_fit:
        shown = lines[: lines_fit - 1]
        shown.append(f"... {len(lines) - len(shown)} more lines (fuzzkit info lists every rule)")
        lines = shown
    ax.set_title(f"rules: {len(rb.rules)}", fontsize=10, loc="left")
    ax.text(
        0.0,
        1.0,
        "\n".join(lines),
        transform=ax.transAxes,
        ha="left",
        va="top",
        family="monospace",
        fontsize=8,
        linespacing=1.35,
    )


def plot_rulebase(rb: RuleBase) -> Any:
    """Membership functions of every variable and the rules of ``rb`` as one Figure.

    Returns a :class:`matplotlib.figure.Figure` with its own Agg canvas (pyplot is not used and
    the global backend is left alone), so a notebook displays it and ``fig.savefig`` writes it.

    Examples
    --------
    >>> fig = plot_rulebase(fuzzkit.load("three_input"))  # doctest: +SKIP
    >>> fig.savefig("three_input.svg")  # doctest: +SKIP
    """
    variables = [("input", v) for v in rb.inputs] + [("output", v) for v in rb.outputs]
    grid = rule_grid(rb)
    height = max(4.6, PANEL_HEIGHT * len(variables) + 0.9)
    fig = new_figure(12.5, height)
    spec = fig.add_gridspec(len(variables), 2, width_ratios=(1.0, 1.0), wspace=0.16, hspace=0.85)
    for row, (kind, var) in enumerate(variables):
        _plot_variable(fig.add_subplot(spec[row, 0]), var, kind, footprint_of(rb))
    rules_ax = fig.add_subplot(spec[:, 1])
    if grid is not None:
        _plot_table(rules_ax, rb, grid)
    else:
        # 8-point monospace at 1.35 line spacing: about 0.15 inch a line.
        _plot_rule_list(rules_ax, rb, int((height - 1.2) / 0.15))
    title = rb.name + (f": {rb.description}" if rb.description else "")
    fig.suptitle(textwrap.shorten(title, 130, placeholder=" ..."), fontsize=11)
    fig.subplots_adjust(left=0.06, right=0.97, top=1 - 0.75 / height, bottom=0.55 / height)
    return fig


def write_rulebase_plot(rb: RuleBase, path: str | os.PathLike[str]) -> Path:
    """Write :func:`plot_rulebase` to ``path`` (.png or .svg by suffix), atomically."""
    figure_format(path, "plot file")
    return save_figure(plot_rulebase(rb), path)
