"""The certified region over the report's stiffness study and latency map (``fuzzkit.analysis``,
docs/stability.md), and the approach speed above which the impact alone passes the safety limit.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

from fuzzkit.analysis.inner_loop import InnerLoop, identify
from fuzzkit.analysis.region import certify_cell, fuzzy_part
from fuzzkit.analysis.regulation import impact_speed_limit
from fuzzkit.studies.experiments import press_experiment
from fuzzkit.studies.latency_sweep import StabilityMap, scaled_default_gains
from fuzzkit.studies.outcome import axis_outcome
from fuzzkit.units import latency_text

#: The plant the report's latency map runs on (the stiffness study runs on the report's).
PLANT = "planar"


def reaction_delay_s(
    inner: InnerLoop, latency: tuple[int, int], engage_samples: int, period_s: float
) -> float:
    """Time from first touch until the correction starts pulling back: the engagement's
    samples, the sensor and command delays, the period a correction waits, and the inner
    loop's lags (their time constants, ``-T / ln(pole)``)."""
    lags = 0.0
    for lo, hi in (inner.a_range, inner.q_range):
        pole = 0.5 * (lo + hi)
        if pole > 0.0:
            lags += -period_s / math.log(pole)
    return (engage_samples + latency[0] + latency[1] + 1) * period_s + lags


def stiffness_lines(
    study: Mapping[tuple[str, str], list[tuple[float, Any]]],
    gains: Mapping[tuple[str, str], Mapping[str, float]],
    rulebase: str,
    plant: str = PLANT,
) -> list[str]:
    """The stiffness study's runs (on ``plant``) against the certificate, per stiffness, and
    the impact speed."""
    inner = identify(plant)
    ks = [k for k, _ in next(iter(study.values()))]
    exp = press_experiment(ks[0] * 1e3)
    latency = exp.latency_periods
    sp = max(abs(s) for s in exp.setpoints)
    delay = reaction_delay_s(inner, latency, exp.engage_samples, exp.scenario.period_s)
    noise = exp.scenario.sensor.noise_std_n
    md = [
        "",
        "### Certified region over the stiffness study",
        "",
        f"Each run above against the stability certificate (`fuzzkit stability`, "
        f"[docs/stability.md](../stability.md)) for the same gains, on the {plant} plant the "
        f"study ran on, latency "
        f"{latency_text(latency)}: **C** certified, **-** not; then how the run ended "
        "(settled, never settled, no contact or tripped: docs/simulation.md). The last column "
        "is the approach speed above which the impact alone passes "
        f"the {exp.force_limit_n:g} N limit: stiffness x speed x {1e3 * delay:.0f} ms (the "
        "engagement, the delays and the inner loop's lags) > limit - set point, whatever the "
        "controller.",
        "",
        "| stiffness N/mm | "
        + " | ".join(f"{c} {lab}" for c, lab in study)
        + " | impact passes the limit above |",
        "|---|" + "---|" * (len(study) + 1),
    ]
    for i, k in enumerate(ks):
        cells = []
        for (ctrl, label), rows in study.items():
            fuzzy = fuzzy_part(rulebase) if ctrl == "fuzzy-pi" else None
            cell = certify_cell(
                exp, ctrl, gains[(ctrl, label)], inner, fuzzy, k, latency, 0.1, noise
            )
            m = rows[i][1]
            ran = axis_outcome(m, bool(m.get("tripped")))  # the words every command uses
            cells.append(f"{'C' if cell.certified else '-'}, {ran}")
        speed = impact_speed_limit(k * 1e3, exp.force_limit_n, delay, sp)
        md.append(f"| {k:g} | " + " | ".join(cells) + f" | {1e3 * speed:.3g} mm/s |")
    return md


def latency_lines(maps: Sequence[StabilityMap], rulebase: str) -> list[str]:
    """The latency map against the certificate: per gain factor, the largest delay certified
    (every smaller one certified too) next to the largest delay the simulation found stable."""
    inner = identify(PLANT)
    exp = press_experiment(1.0e4)
    noise = exp.scenario.sensor.noise_std_n
    md = [
        "",
        "Against the certificate (same press, 10 N/mm, sensor delay only; "
        "[docs/stability.md](../stability.md)): the largest delay up to which every delay is "
        "certified, next to the largest the simulation found stable. A certified delay above "
        "the simulated one would be a false certificate.",
        "",
        "| gain factor | "
        + " | ".join(f"{m.controller}: certified / simulated" for m in maps)
        + " |",
        "|---|" + "---|" * len(maps),
    ]
    for fi, factor in enumerate(maps[0].factors):
        cells = []
        for m in maps:
            fuzzy = fuzzy_part(rulebase) if m.controller == "fuzzy-pi" else None
            g = scaled_default_gains(m.controller, factor)
            cert: int | None = None
            for d in m.delays:
                c = certify_cell(exp, m.controller, g, inner, fuzzy, 10.0, (d, 0), 0.1, noise)
                if not c.certified:
                    break
                cert = d
            sim = m.boundary()[m.factors[fi]]
            cells.append(f"{'none' if cert is None else cert} / {'none' if sim is None else sim}")
        md.append(f"| {factor:g} | " + " | ".join(cells) + " |")
    return md
