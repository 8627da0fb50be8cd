"""Never settled, no contact and tripped: three words, defined once (fuzzkit.studies.outcome),
said alike in text, JSON and figures; and a tripped run drawn as one (issue 33 item 4)."""

from __future__ import annotations

import json
from dataclasses import replace
from typing import Any

import numpy as np
import pytest

from fuzzkit.cli import main
from fuzzkit.studies.outcome import (
    NEVER_SETTLED,
    NO_CONTACT,
    OUTCOMES,
    SETTLED,
    TRIPPED,
    axis_outcome,
    settling_text,
)


def test_the_words_are_four_and_distinct() -> None:
    assert len(set(OUTCOMES)) == 4 and "-" not in OUTCOMES
    assert {TRIPPED, NO_CONTACT, NEVER_SETTLED} == {"tripped", "no contact", "never settled"}


@pytest.mark.parametrize(
    "metrics, tripped, outcome, text",
    [
        ({"contact_lost_s": 0.0, "settling_time_s": 0.123}, False, SETTLED, "0.12 s"),
        ({"contact_lost_s": 0.0, "settling_time_s": None}, False, NEVER_SETTLED, NEVER_SETTLED),
        ({"contact_lost_s": None, "settling_time_s": None}, False, NO_CONTACT, NO_CONTACT),
        ({"contact_lost_s": 3.0, "settling_time_s": None}, True, TRIPPED, TRIPPED),
        ({"contact_lost_s": 0.0, "settling_time_s": 0.1}, True, TRIPPED, TRIPPED),
    ],
)
def test_axis_outcome(metrics: dict[str, Any], tripped: bool, outcome: str, text: str) -> None:
    assert axis_outcome(metrics, tripped) == outcome
    assert settling_text(metrics, tripped) == text


def _json(capsys: pytest.CaptureFixture[str], *args: str) -> dict[str, Any]:
    assert main(["simulate", *args, "--json"]) == 0
    data: dict[str, Any] = json.loads(capsys.readouterr().out)
    return data


def test_each_word_is_what_simulate_prints_and_writes(
    capsys: pytest.CaptureFixture[str],
) -> None:
    tripped = _json(capsys, "E1", "--stiffness", "100")  # the default gains trip at 100 N/mm
    assert tripped["tripped"] is True
    assert {m["outcome"] for m in tripped["axes"].values()} == {TRIPPED}
    held = _json(capsys, "E1")
    assert held["tripped"] is False
    assert held["axes"]["z"]["outcome"] == SETTLED
    assert held["axes"]["z"]["settling_time_s"] is not None
    assert main(["simulate", "E1", "--stiffness", "100"]) == 0
    out = capsys.readouterr().out
    assert "settling tripped," in out and "settling - s" not in out


def test_no_contact_and_never_settled_from_real_runs() -> None:
    from fuzzkit.loop.python_loop import run
    from fuzzkit.studies.experiments import experiment
    from fuzzkit.studies.metrics import summary

    short = run(experiment("E1"), "planar", "pi", duration_s=1.0)  # contact comes at 1.87 s
    assert not short.in_contact.any()
    assert {m["outcome"] for m in summary(short)["axes"].values()} == {NO_CONTACT}
    # E2 touches its workpiece at 0.99 s: stopped 0.1 s later, the force is still rising
    e2 = run(experiment("E2"), "planar", "pi", duration_s=1.1)
    z = summary(e2)["axes"]["z"]
    assert e2.in_contact.any() and not e2.tripped
    assert z["settling_time_s"] is None and z["outcome"] == NEVER_SETTLED


def test_the_compare_table_says_the_word() -> None:
    from fuzzkit.cli.simulation import comparison_table

    axes = {
        "setpoint": 10.0,
        "first_contact_s": 1.0,
        "overshoot_pct": 3.0,
        "settling_time_s": None,
        "steady_state_error_mean": 0.0,
        "steady_state_error_std": 0.0,
        "rms_error": 0.1,
        "peak_force": 12.0,
        "contact_lost_s": 0.0,
    }
    rows = [
        {"experiment": "E1", "controller": "pi", "tripped": False, "axes": {"z": axes}},
        {"experiment": "E1", "controller": "fuzzy-pi", "tripped": True, "axes": {"z": axes}},
    ]
    table = comparison_table(rows).splitlines()
    assert "never settled" in table[2] and "tripped" in table[3]


def test_a_tripped_run_draws_no_frozen_error() -> None:
    """After the trip the controller computes no error: the figure's error and increment
    lines end at the trip (a frozen last value was drawn for 3 s before), and the panels and
    title say "tripped"."""
    from fuzzkit.loop.python_loop import load_surface, run
    from fuzzkit.studies.experiments import experiment, with_stiffness
    from fuzzkit.viz.run_figure import run_figure

    surface = load_surface("macvicar_whelan")
    result = run(with_stiffness(experiment("E1"), 100e3), "planar", "fuzzy-pi", surface=surface)
    assert result.trip_time_s is not None
    after = result.t > result.trip_time_s
    # the recorded error is frozen after the trip: what the figure used to draw
    assert np.ptp(result.e[after, 2]) == 0.0 and result.e[after, 2][0] != 0.0
    fig = run_figure(result)
    ax_e = fig.axes[1]
    y = np.asarray(ax_e.lines[0].get_ydata(), dtype=float)
    assert np.isnan(y[after]).all()
    assert np.isfinite(y[~after][-1])  # drawn up to the trip
    texts = [t.get_text() for ax in fig.axes for t in ax.texts]
    assert any(t.startswith("tripped: retreating") for t in texts)
    assert "settling: z tripped, x tripped" in fig._suptitle.get_text()
    # an untripped run: nothing masked, no such note
    held = run_figure(replace(result, trip_time_s=None, tripped=False))
    assert not any("retreating" in t.get_text() for ax in held.axes for t in ax.texts)
