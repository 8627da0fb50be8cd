"""The paper's claims judged from run summaries, per setting, and the conclusion they support.

A *setting* is a plant, a gains set (``default``, ``matched``, ``tuned``) and an operating
condition (:data:`NOMINAL`: each experiment's own latency and stiffness; or another latency, or
another contact stiffness). :func:`assess_claims` judges the paper's sec. 4.1 claims in one
setting from the metrics of its runs; the Markdown helpers lay the verdicts out as tables, and
:func:`claims_conclusion` writes the paragraph that follows from them. Nothing here runs a
simulation: ``fuzzkit.report.build`` does, and hands the summaries over.

A claim compares two runs; when the safety limit tripped either of them, its metrics describe a
stopped controller, and the claim is *not judged* in that setting (it neither holds nor fails).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from fuzzkit.errors import ConfigError

Key = tuple[str, str, str, str]  # plant, experiment, controller, gains label

#: The condition label of each experiment's own latency and stiffness.
NOMINAL = "nominal"

#: Differences smaller than these are "no clear difference" when checking a claim:
#: (absolute, relative to the larger value).
OVERSHOOT_TOL = (0.5, 0.10)  # percentage points, fraction
SETTLING_TOL = (0.02, 0.10)  # s, fraction
RMS_TOL = (0.01, 0.10)  # N, fraction
#: E3 "similar": per axis, RMS and settling time within this fraction (or the absolute floor).
SIMILAR_REL = 0.25
SIMILAR_ABS = {"rms_error": 0.05, "settling_time_s": 0.25}

#: The gains set that compares like with like (docs/comparison.md).
LIKE_FOR_LIKE = "matched"


@dataclass(frozen=True, slots=True)
class ClaimResult:
    """One of the paper's claims checked in one setting (plant, gains, condition).

    ``judged`` is False when a run the claim needs tripped the safety limit; ``holds`` is then
    False too and ``verdict`` says which run tripped.
    """

    claim: str
    plant: str
    gains: str
    holds: bool
    verdict: str
    evidence: str
    condition: str = NOMINAL
    judged: bool = True

    @property
    def setting(self) -> str:
        """``plant/gains``, followed by ``at CONDITION`` away from the nominal condition."""
        base = f"{self.plant}/{self.gains}"
        return base if self.condition == NOMINAL else f"{base} at {self.condition}"


def _run(summaries: Mapping[Key, Mapping[str, Any]], key: Key) -> Mapping[str, Any]:
    data = summaries.get(key)
    if data is None:
        raise ConfigError(f"no run for {'/'.join(key)} (needed by a claim)")
    return data


def _axis(summaries: Mapping[Key, Mapping[str, Any]], key: Key, axis: str) -> Mapping[str, Any]:
    axes: Mapping[str, Mapping[str, Any]] = _run(summaries, key)["axes"]
    if axis not in axes:
        raise ConfigError(f"run {'/'.join(key)} has no force-controlled axis {axis}")
    return axes[axis]


def _num(v: Any, never: float = math.inf) -> float:
    return never if v is None else float(v)


def _compare(a: float, b: float, tol: tuple[float, float]) -> int:
    """-1 if a is clearly smaller than b, +1 if clearly larger, 0 within the tolerance."""
    if math.isinf(a) and math.isinf(b):
        return 0
    margin = max(tol[0], tol[1] * max(abs(a), abs(b)) if math.isfinite(max(a, b)) else 0.0)
    if a < b - margin:
        return -1
    if a > b + margin:
        return 1
    return 0


def fmt(v: Any, unit: str = "", digits: int = 2) -> str:
    """A metric for a table: ``never`` for a missing time, ``-`` for another missing value."""
    if v is None:
        return "never" if unit == " s" else "-"
    return f"{float(v):.{digits}f}{unit}"


def assess_claims(
    summaries: Mapping[Key, Mapping[str, Any]],
    plant: str,
    gains: str,
    condition: str = NOMINAL,
) -> list[ClaimResult]:
    """Check the paper's sec. 4.1 conclusions against run summaries.

    Parameters
    ----------
    summaries : ``{(plant, experiment, controller, gains):
        fuzzkit.studies.metrics.summary(...)}``, all run in one condition.
    plant, gains : which plant and gains set (``default`` / ``matched`` / ``tuned``) to judge.
    condition : the label of the condition the runs were made in (for the tables).

    Returns
    -------
    One :class:`ClaimResult` per claim, in the paper's order. "Clearly" better means beyond
    the tolerances of this module (``OVERSHOOT_TOL`` ...), else "no clear difference". A claim
    whose runs tripped the safety limit is not judged.

    Raises
    ------
    ConfigError
        A run the claims need is missing.
    """

    def k(exp: str, ctrl: str) -> Key:
        return (plant, exp, ctrl, gains)

    out: list[ClaimResult] = []

    def add(claim: str, exp: str, holds: bool, verdict: str, evidence: str) -> None:
        tripped = [
            name
            for ctrl, name in (("pi", "PI"), ("fuzzy-pi", "fuzzy-PI"))
            if _run(summaries, k(exp, ctrl)).get("tripped")
        ]
        if tripped:
            verdict = f"not judged ({' and '.join(tripped)} tripped the safety limit)"
            out.append(ClaimResult(claim, plant, gains, False, verdict, evidence, condition, False))
            return
        out.append(ClaimResult(claim, plant, gains, holds, verdict, evidence, condition))

    def verdict_of(sign: int, want: int) -> tuple[bool, str]:
        if sign == want:
            return True, "holds"
        if sign == 0:
            return False, "does not hold (no clear difference)"
        return False, "does not hold (the opposite)"

    # E1: fuzzy-PI less overshoot, faster settling (z, 10 N).
    pi, fz = _axis(summaries, k("E1", "pi"), "z"), _axis(summaries, k("E1", "fuzzy-pi"), "z")
    s = _compare(_num(fz["overshoot_pct"], 0.0), _num(pi["overshoot_pct"], 0.0), OVERSHOOT_TOL)
    add(
        "E1: fuzzy-PI overshoots less than PI",
        "E1",
        *verdict_of(s, -1),
        f"z overshoot fuzzy-PI {fmt(fz['overshoot_pct'], ' %', 1)} vs "
        f"PI {fmt(pi['overshoot_pct'], ' %', 1)}",
    )
    s = _compare(_num(fz["settling_time_s"]), _num(pi["settling_time_s"]), SETTLING_TOL)
    add(
        "E1: fuzzy-PI settles faster than PI",
        "E1",
        *verdict_of(s, -1),
        f"z settling fuzzy-PI {fmt(fz['settling_time_s'], ' s')} vs "
        f"PI {fmt(pi['settling_time_s'], ' s')}",
    )
    # E2: PI finer on small disturbances (RMS while moving), PI larger initial overshoot.
    pi, fz = _axis(summaries, k("E2", "pi"), "z"), _axis(summaries, k("E2", "fuzzy-pi"), "z")
    s = _compare(_num(pi["rms_error"]), _num(fz["rms_error"]), RMS_TOL)
    add(
        "E2: PI has the finer resolution on small disturbances",
        "E2",
        *verdict_of(s, -1),
        f"z RMS error while moving PI {fmt(pi['rms_error'], ' N')} vs fuzzy-PI "
        f"{fmt(fz['rms_error'], ' N')} (steady std {fmt(pi['steady_state_error_std'], ' N')}"
        f" vs {fmt(fz['steady_state_error_std'], ' N')})",
    )
    s = _compare(_num(pi["overshoot_pct"], 0.0), _num(fz["overshoot_pct"], 0.0), OVERSHOOT_TOL)
    add(
        "E2: PI overshoots more at the start",
        "E2",
        *verdict_of(s, 1),
        f"z overshoot PI {fmt(pi['overshoot_pct'], ' %', 1)} vs "
        f"fuzzy-PI {fmt(fz['overshoot_pct'], ' %', 1)}",
    )
    # E3: similar results, x behaves like z.
    diffs: list[str] = []
    notes: list[str] = []
    for axis in ("z", "x"):
        pi, fz = _axis(summaries, k("E3", "pi"), axis), _axis(summaries, k("E3", "fuzzy-pi"), axis)
        for metric, unit in (("rms_error", " N"), ("settling_time_s", " s")):
            a, b = _num(pi[metric]), _num(fz[metric])
            tol = (SIMILAR_ABS[metric], SIMILAR_REL)
            what = metric.split("_")[0]
            note = f"{axis} {what} PI {fmt(pi[metric], unit)} vs {fmt(fz[metric], unit)}"
            notes.append(note)
            if _compare(a, b, tol) != 0:
                diffs.append(note)
    add(
        "E3: neither controller is better (x behaves like z)",
        "E3",
        not diffs,
        "holds" if not diffs else "does not hold (" + "; ".join(diffs) + ")",
        "; ".join(notes),
    )
    return out


# --------------------------------------------------------------------------------------------
# Markdown
# --------------------------------------------------------------------------------------------


def claims_markdown(results: Sequence[ClaimResult]) -> str:
    """The claim-by-claim table (one row per claim and setting, with the numbers)."""
    conditions = any(c.condition != NOMINAL for c in results)
    head = "| claim (paper, sec. 4.1) | plant | gains | "
    head += "condition | verdict | numbers |" if conditions else "verdict | numbers |"
    lines = [head, "|---" * head.count(" | ") + "|---|"]
    for c in results:
        verdict = f"**{c.verdict}**" if c.holds else c.verdict
        cond = f" {c.condition} |" if conditions else ""
        lines.append(f"| {c.claim} | {c.plant} | {c.gains} |{cond} {verdict} | {c.evidence} |")
    return "\n".join(lines)


def _cell(c: ClaimResult) -> str:
    if not c.judged:
        both = "PI and fuzzy-PI" in c.verdict
        return (
            "trip (both)" if both else "trip (fuzzy-PI)" if "fuzzy-PI" in c.verdict else "trip (PI)"
        )
    if c.holds:
        return "**yes**"
    return "no (=)" if "no clear difference" in c.verdict else "no"


def verdict_matrix_markdown(results: Sequence[ClaimResult], plant: str) -> str:
    """The verdicts of one plant at a glance: a row per claim and gains set, a column per
    condition; ``yes`` (holds), ``no`` (the opposite or a difference the claim does not
    predict), ``no (=)`` (no clear difference), ``trip (PI|fuzzy-PI|both)`` (not judged: that
    controller's run tripped the safety limit)."""
    rs = [c for c in results if c.plant == plant]
    conditions = list(dict.fromkeys(c.condition for c in rs))
    cells: dict[tuple[str, str, str], ClaimResult] = {
        (c.claim, c.gains, c.condition): c for c in rs
    }
    rows = list(dict.fromkeys((c.claim, c.gains) for c in rs))
    lines = [
        "| claim | gains | " + " | ".join(conditions) + " |",
        "|---|---|" + "---|" * len(conditions),
    ]
    for claim, gains in rows:
        row = [
            _cell(cells[(claim, gains, cond)]) if (claim, gains, cond) in cells else ""
            for cond in conditions
        ]
        lines.append(f"| {claim} | {gains} | " + " | ".join(row) + " |")
    return "\n".join(lines)


def _by_claim(results: Sequence[ClaimResult]) -> dict[str, list[ClaimResult]]:
    by_claim: dict[str, list[ClaimResult]] = {}
    for c in results:
        by_claim.setdefault(c.claim, []).append(c)
    return by_claim


def _where(results: Sequence[ClaimResult]) -> str:
    """Where a claim holds, grouped by plant/gains: ``arm6/tuned at 0+0, 5 N/mm`` or
    ``planar/matched except at 1000 N/mm`` (only judged results count)."""
    groups: dict[str, list[ClaimResult]] = {}
    for r in results:
        if r.judged:
            groups.setdefault(f"{r.plant}/{r.gains}", []).append(r)
    parts = []
    for name, rs in groups.items():
        held = [r.condition for r in rs if r.holds]
        failed = [r.condition for r in rs if not r.holds]
        if not held:
            continue
        if len(rs) == 1:
            parts.append(rs[0].setting)
        elif not failed:
            parts.append(f"{name} in every condition")
        elif len(held) <= len(failed):
            parts.append(f"{name} at {', '.join(held)}")
        else:
            parts.append(f"{name} except at {', '.join(failed)}")
    return "; ".join(parts)


def claims_summary(results: Sequence[ClaimResult]) -> str:
    """One line per claim: in how many of the judged settings it holds, and where."""
    lines = []
    for claim, rs in _by_claim(results).items():
        judged = [r for r in rs if r.judged]
        n = sum(r.holds for r in judged)
        skipped = len(rs) - len(judged)
        tail = f"; {skipped} not judged, as a run tripped" if skipped else ""
        if judged and n == len(judged):
            lines.append(f"- {claim}: **holds** in every setting judged ({len(judged)}{tail}).")
        elif n == 0:
            lines.append(
                f"- {claim}: **does not hold** in any setting judged ({len(judged)}{tail})."
            )
        else:
            where = _where(judged)
            count = f"{n} of {len(judged)} settings judged"
            lines.append(f"- {claim}: holds in {count} ({where}){tail}.")
    return "\n".join(lines)


def claims_conclusion(results: Sequence[ClaimResult]) -> str:
    """One paragraph that follows from the verdict tables: which claims hold in every setting
    judged, which in none, on which settings the rest depend, and what the like-for-like
    (matched) setting says about each; settings where a run tripped are left out and counted.
    """
    by_claim = _by_claim(results)

    def judged(claim: str) -> list[ClaimResult]:
        return [r for r in by_claim[claim] if r.judged]

    always = [k for k in by_claim if judged(k) and all(r.holds for r in judged(k))]
    never = [k for k in by_claim if not any(r.holds for r in judged(k))]
    mixed = [k for k in by_claim if k not in always and k not in never]
    n_settings = len({r.setting for r in results})
    parts = [f"Of the paper's {len(by_claim)} claims checked here in {n_settings} settings,"]
    parts.append(
        f"{len(always)} {'holds' if len(always) == 1 else 'hold'} in every setting judged "
        f"({'; '.join(always)})"
        if always
        else "none holds in every setting"
    )
    parts.append(
        f"and {len(never)} in none ({'; '.join(never)})." if never else "and none fails in all."
    )
    sentences = [" ".join(parts)]
    for claim in mixed:
        rs = judged(claim)
        n_held = sum(r.holds for r in rs)
        like = [r for r in rs if r.gains == LIKE_FOR_LIKE]
        text = (
            f'"{claim}" depends on the setting: it holds in {n_held} of {len(rs)} ({_where(rs)}).'
        )
        if like:
            n_like = sum(r.holds for r in like)
            plants = {r.plant for r in like}
            if len(like) == len(plants):  # one condition per plant: say it per plant
                where = (
                    "holds on every plant"
                    if n_like == len(like)
                    else "holds on no plant"
                    if n_like == 0
                    else f"holds on {n_like} of {len(like)} plants"
                )
            else:
                where = (
                    f"holds in all {len(like)} of its settings"
                    if n_like == len(like)
                    else f"holds in none of its {len(like)} settings"
                    if n_like == 0
                    else f"holds in {n_like} of its {len(like)} settings"
                )
            text += f" With matched small-signal gains (the like-for-like comparison) it {where}."
        sentences.append(text)
    skipped = [r for r in results if not r.judged]
    if skipped:
        conds = list(dict.fromkeys(r.condition for r in skipped))
        sentences.append(
            f"{len(skipped)} verdicts are not judged because a controller tripped the safety "
            f"limit ({', '.join(conds)}): a tripped run stops the task, so its overshoot and "
            "settling say nothing about the claim."
        )
        sentences += _one_sided_trips(skipped)
    sentences.append(
        "A verdict that changes with the gains, the latency or the stiffness is a property of "
        "that setting, not of fuzzy versus linear control."
    )
    return " ".join(sentences)


def _one_sided_trips(skipped: Sequence[ClaimResult]) -> list[str]:
    """Sentences naming the experiments and settings where only one controller tripped: there
    the other one did the task, a difference the claims do not cover."""
    out = []
    for name in ("PI", "fuzzy-PI"):
        only = f"({name} tripped the safety limit)"
        where = list(
            dict.fromkeys(
                f"{r.claim.split(':')[0]} {r.setting}" for r in skipped if only in r.verdict
            )
        )
        if where:
            other = "fuzzy-PI" if name == "PI" else "PI"
            out.append(f"Only {name} tripped, and {other} held the force, in {'; '.join(where)}.")
    return out
