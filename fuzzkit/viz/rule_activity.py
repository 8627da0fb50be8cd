"""The fuzzy-PI's strongest rules in every period of a run, for its recording.

Recomputed after the run from the recorded ``e`` and ``de`` and the gains the run used, as the
controller saw them (``clip(Ki*e)``, ``clip(Kp*de)``; :class:`fuzzkit.control.controllers.
FuzzyPI`): one batched firing-strength evaluation for the whole run, so a recording costs
milliseconds more, and the loop itself is untouched (the compiled loop has no rule base at all,
only its table). Periods before the engagement, after a trip and without a valid sample carry
nothing: the controller did not run then.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.fuzzy.describe import format_expression
from fuzzkit.fuzzy.model import RuleBase
from fuzzkit.loop.result import RunResult
from fuzzkit.studies.run_table import period_status

#: Rules shown per period.
TOP_RULES = 3


@dataclass(frozen=True, slots=True)
class AxisRules:
    """One force-controlled axis: the periods the controller ran, their strongest rules (rule
    indices from 0, strongest first) and those rules' firing strengths."""

    axis: str
    t: npt.NDArray[np.float64]
    rules: npt.NDArray[np.intp]  # (periods, TOP_RULES)
    strengths: npt.NDArray[np.float64]  # (periods, TOP_RULES)


def strongest_rules(
    rb: RuleBase, result: RunResult, gains: Mapping[str, Any], top: int = TOP_RULES
) -> list[AxisRules]:
    """The ``top`` strongest rules of every controlled period, per force-controlled axis.

    ``gains``: the fuzzy-PI's complete gains (``ki``, ``kp``) the run used, or per axis
    (``{"z": {"ki": ..}}``, as a controller spec gives them). ``rb``'s inputs in role order
    (the error, then its change: ``fuzzkit.control.spec.role_ordered`` under a spec).
    """
    from fuzzkit.control.loop_rulebase import role_names
    from fuzzkit.fuzzy.inference import engine_for

    engine = engine_for(rb)
    ran = np.array([s == "engaged" for s in period_status(result)], dtype=bool)
    top = min(top, len(rb.rules))
    e_name, de_name, _ = role_names(rb)
    out = []
    for i, axis in enumerate("xyz"):
        if not result.experiment.selection[i]:
            continue
        g = gains.get(axis, gains)
        en = np.clip(g["ki"] * result.e[ran, i], -1.0, 1.0)
        den = np.clip(g["kp"] * result.de[ran, i], -1.0, 1.0)
        firing = engine.firing_strengths({e_name: en, de_name: den})
        order = np.argsort(-firing, axis=1, kind="stable")[:, :top]
        out.append(AxisRules(axis, result.t[ran], order, np.take_along_axis(firing, order, axis=1)))
    return out


def rule_label(rb: RuleBase, index: int) -> str:
    """A rule as a short line: ``e is PS and de is ZR -> du is PS``."""
    rule = rb.rules[index]
    then = ", ".join(f"{c.variable} is {c.term}" for c in rule.consequents)
    return f"{format_expression(rule.antecedent)} -> {then}"


@dataclass(frozen=True, slots=True)
class RuleRecording:
    """What a run recording logs about the fuzzy-PI's rules (:func:`rule_recording`)."""

    rulebase: RuleBase
    activity: list[AxisRules]

    def log(self, rec: Any) -> None:
        """Log it into the recording ``rec``."""
        log_rule_activity(rec, self.rulebase, self.activity)


def rule_recording(
    result: RunResult, rulebase: RuleBase, gains: Mapping[str, Any]
) -> RuleRecording | None:
    """The rule activity of a fuzzy-PI run for its recording (None for any other controller).

    ``gains``: the fuzzy-PI's gains as given to the run (overrides of the defaults), or its
    complete gains per axis (a controller spec's).
    """
    from fuzzkit.studies.experiments import DEFAULT_GAINS

    if result.controller != "fuzzy-pi":
        return None
    per_axis = any(isinstance(v, Mapping) for v in gains.values())
    full = dict(gains) if per_axis else {**DEFAULT_GAINS["fuzzy-pi"], **gains}
    return RuleRecording(rulebase, strongest_rules(rulebase, result, full))


def log_rule_activity(rec: Any, rb: RuleBase, activity: list[AxisRules]) -> None:
    """Log each axis's strongest rules under ``control/rules/<axis>``: a text line per period
    (``0.70 e is PS and de is ZR -> du is PS | 0.30 ...``) and the strongest rule's strength
    as a series (``control/rules/<axis>/strongest``)."""
    import rerun as rr

    labels = [rule_label(rb, r) for r in range(len(rb.rules))]
    for a in activity:
        if not len(a.t):
            continue
        entity = f"control/rules/{a.axis}"
        text = [
            " | ".join(
                f"{s:.2f} {labels[r]}" for r, s in zip(rules, strengths, strict=True) if s > 0
            )
            or "no rule fires"
            for rules, strengths in zip(a.rules, a.strengths, strict=True)
        ]
        times = rr.TimeColumn("sim_time", duration=a.t)
        rec.send_columns(entity, indexes=[times], columns=rr.TextLog.columns(text=text))
        rec.log(
            f"{entity}/strongest",
            rr.SeriesLines(colors=[(120, 60, 200)], names=[f"strongest rule {a.axis} (0-1)"]),
            static=True,
        )
        rec.send_columns(
            f"{entity}/strongest",
            indexes=[times],
            columns=rr.Scalars.columns(scalars=a.strengths[:, 0]),
        )
