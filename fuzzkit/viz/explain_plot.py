"""A figure of one point's inference (``fuzzkit eval --explain --png``): per output, its terms,
the aggregated set and the defuzzified value; per Sugeno output, each term's value at the point
with its activation."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from fuzzkit.fuzzy.describe import axis_label, num
from fuzzkit.fuzzy.explain import Explanation
from fuzzkit.fuzzy.model import RuleBase
from fuzzkit.viz.figures import new_figure, save_figure
from fuzzkit.viz.rulebase_plot import term_curve


def explanation_figure(rb: RuleBase, explanation: Explanation) -> Any:
    """The figure (matplotlib, no pyplot): one panel per output."""
    outs = explanation.outputs
    fig = new_figure(9.5, 2.8 * len(outs) + 0.7)
    axes = fig.subplots(len(outs), 1, squeeze=False)
    for ax_row, out in zip(axes, outs, strict=True):
        ax = ax_row[0]
        var = rb.output(out.name)
        if len(out.y):
            for k, term in enumerate(var.terms):
                x, mu = term_curve(var, k)
                ax.plot(x, mu, color="0.6", lw=0.8)
                ax.annotate(term.name, (float(x[int(mu.argmax())]), 1.02), ha="center", fontsize=7)
            ax.fill_between(out.y, out.mu, color="tab:blue", alpha=0.35, lw=0)
            ax.plot(out.y, out.mu, color="tab:blue", lw=1.2, label="aggregated set")
        else:
            for name, z in out.term_values.items():
                a = out.activations[name]
                ax.vlines(z, 0.0, a, color="tab:blue", lw=2.0)
                ax.annotate(
                    f"{name} {num(a)}",
                    (z, a),
                    xytext=(2, 2),
                    textcoords="offset points",
                    fontsize=7,
                )
        ax.axvline(
            out.value, color="tab:red", lw=1.5, label=f"{out.defuzzifier} = {num(out.value)}"
        )
        ax.set_xlim(var.low, var.high)
        ax.set_ylim(0.0, 1.12)
        ax.set_xlabel(axis_label(var))
        ax.set_ylabel("membership" if len(out.y) else "activation")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    point = ", ".join(f"{i.name} = {num(i.value)}" for i in explanation.inputs)
    fired = len(explanation.rules)
    fig.suptitle(
        f"{explanation.rulebase} at {point}: {fired} of {len(rb.rules)} rules fire", fontsize=10
    )
    fig.tight_layout()
    return fig


def write_explanation_png(
    rb: RuleBase, explanation: Explanation, path: str | os.PathLike[str]
) -> Path:
    """Write :func:`explanation_figure` to ``path`` (.png or .svg), atomically."""
    return save_figure(explanation_figure(rb, explanation), path)
