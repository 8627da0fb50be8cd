"""Membership functions of every variable, drawn as a PNG: fuzzkit's ``plotmf``.

One panel per variable, its terms over its range (and 10 % beyond it when the rule base
evaluates inputs where they are, ``out_of_range: extend``, so that what happens outside is
visible). Sugeno output terms (constant, linear) have no membership function and are listed
in the panel instead.
"""

from __future__ import annotations

import io
import os
from pathlib import Path

import numpy as np

from fuzzkit.fileio import write_atomic
from fuzzkit.fuzzy import membership
from fuzzkit.fuzzy.model import RuleBase, Variable

#: Samples per panel; piecewise-linear vertices are added so corners are drawn exactly.
SAMPLES = 801


def _panel_x(var: Variable, extend: bool) -> np.ndarray:
    pad = 0.1 * (var.high - var.low) if extend else 0.0
    x = np.linspace(var.low - pad, var.high + pad, SAMPLES)
    corners = [p for t in var.terms if t.is_piecewise_linear for p in t.params]
    inside = [p for p in corners if x[0] <= p <= x[-1]]
    return np.unique(np.concatenate([x, np.asarray(inside, dtype=np.float64)]))


def write_terms_png(rb: RuleBase, path: str | os.PathLike[str]) -> Path:
    """Draw every input's and output's terms to a PNG (matplotlib, Agg), atomically."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    variables = [("input", v) for v in rb.inputs] + [("output", v) for v in rb.outputs]
    fig = Figure(figsize=(7, 2.2 * len(variables) + 0.6), dpi=100)
    axes = fig.subplots(len(variables), 1, squeeze=False)[:, 0]
    for ax, (kind, var) in zip(axes, variables, strict=True):
        extend = kind == "input" and rb.out_of_range == "extend"
        x = _panel_x(var, extend)
        listed = []
        for term in var.terms:
            if term.shape not in membership.SHAPES:  # Sugeno terms: no membership function
                listed.append(f"{term.name}: {term.shape} {list(term.params)}")
                continue
            if term.shape == "singleton":
                ax.vlines(term.params[0], 0, 1, label=term.name)
                continue
            ax.plot(x, membership.evaluate_term(term, x), label=term.name)
        if listed:
            ax.text(0.01, 0.5, "\n".join(listed), transform=ax.transAxes, va="center")
        ax.axvspan(var.low, var.high, color="0.94", zorder=0)
        ax.set_xlim(x[0], x[-1])
        ax.set_ylim(-0.05, 1.05)
        ax.set_ylabel("membership")
        ax.set_title(f"{kind} {var.name}  [{var.low:g}, {var.high:g}]", fontsize=10)
        if len(listed) < len(var.terms):
            ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize=8, frameon=False)
    fig.suptitle(f"{rb.name}: membership functions (range shaded)")
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    return write_atomic(path, buf.getvalue())
