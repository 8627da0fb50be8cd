"""The comparison report: claims follow the numbers, and the files it writes."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import pytest

from fuzzkit.control.gains import GainsEntry, write_gains
from fuzzkit.errors import ConfigError
from fuzzkit.report.build import build_report, default_gain_sentence, quick_options
from fuzzkit.report.grid import Condition, conditions
from fuzzkit.report.tuned import TuningSetup, setup_from_provenance
from fuzzkit.report.verdicts import (
    NOMINAL,
    ClaimResult,
    Key,
    assess_claims,
    claims_conclusion,
    claims_summary,
    verdict_matrix_markdown,
)


def _axis(
    overshoot: float | None, settle: float | None, rms: float | None, std: float = 0.05
) -> dict[str, Any]:
    return {
        "setpoint": 10.0,
        "overshoot_pct": overshoot,
        "settling_time_s": settle,
        "steady_state_error_mean": 0.0,
        "steady_state_error_std": std,
        "rms_error": rms,
        "peak_force": 10.0,
        "contact_lost_s": 0.0,
    }


def _paper_like() -> dict[Key, dict[str, Any]]:
    """Metrics shaped like the paper's findings: every claim should hold."""
    s: dict[Key, dict[str, Any]] = {}

    def put(exp: str, ctrl: str, axes: dict[str, dict[str, Any]]) -> None:
        s[("planar", exp, ctrl, "default")] = {"experiment": exp, "controller": ctrl, "axes": axes}

    put("E1", "pi", {"z": _axis(30.0, 1.2, None)})
    put("E1", "fuzzy-pi", {"z": _axis(5.0, 0.4, None)})
    put("E2", "pi", {"z": _axis(20.0, 2.0, 0.30, 0.05)})
    put("E2", "fuzzy-pi", {"z": _axis(8.0, 2.0, 0.50, 0.12)})
    same = {"z": _axis(2.0, 1.0, 0.40), "x": _axis(3.0, 1.5, 0.20)}
    put("E3", "pi", copy.deepcopy(same))
    put("E3", "fuzzy-pi", copy.deepcopy(same))
    return s


def _verdicts(s: dict[Key, dict[str, Any]]) -> dict[str, tuple[bool, str]]:
    return {c.claim: (c.holds, c.verdict) for c in assess_claims(s, "planar", "default")}


def test_paper_like_numbers_make_every_claim_hold() -> None:
    v = _verdicts(_paper_like())
    assert len(v) == 5
    assert all(holds for holds, _ in v.values()), v
    text = claims_summary(assess_claims(_paper_like(), "planar", "default"))
    assert text.count("**holds** in every setting judged") == 5


def test_reversed_numbers_make_the_claims_fail_and_say_so() -> None:
    s = _paper_like()
    e1 = s[("planar", "E1", "pi", "default")], s[("planar", "E1", "fuzzy-pi", "default")]
    s[("planar", "E1", "pi", "default")], s[("planar", "E1", "fuzzy-pi", "default")] = e1[1], e1[0]
    s[("planar", "E2", "pi", "default")]["axes"]["z"]["rms_error"] = 0.5  # equal to fuzzy-PI
    s[("planar", "E3", "fuzzy-pi", "default")]["axes"]["x"]["settling_time_s"] = None  # never
    v = _verdicts(s)
    assert v["E1: fuzzy-PI overshoots less than PI"] == (False, "does not hold (the opposite)")
    assert v["E1: fuzzy-PI settles faster than PI"] == (False, "does not hold (the opposite)")
    assert v["E2: PI has the finer resolution on small disturbances"] == (
        False,
        "does not hold (no clear difference)",
    )
    holds, verdict = v["E3: neither controller is better (x behaves like z)"]
    assert not holds and "x settling PI 1.50 s vs never" in verdict
    text = claims_summary(assess_claims(s, "planar", "default"))
    assert "E1: fuzzy-PI overshoots less than PI: **does not hold**" in text


def test_differences_within_tolerance_are_no_clear_difference() -> None:
    s = _paper_like()
    s[("planar", "E1", "fuzzy-pi", "default")]["axes"]["z"]["overshoot_pct"] = 29.0  # vs 30 %
    v = _verdicts(s)
    assert v["E1: fuzzy-PI overshoots less than PI"] == (
        False,
        "does not hold (no clear difference)",
    )


def test_a_missing_run_is_a_clear_error() -> None:
    s = _paper_like()
    del s[("planar", "E2", "pi", "default")]
    with pytest.raises(ConfigError, match="no run for planar/E2/pi/default"):
        assess_claims(s, "planar", "default")


def test_report_writes_markdown_figures_and_recordings(tmp_path: Path) -> None:
    """With given gains (no tuning), in the quick mode: every file, verdict tables that are the
    ones assess_claims derives, in every setting, and the tuned-vs-default table per case."""
    gains_dir = tmp_path / "gains"
    gains_dir.mkdir()
    write_gains(gains_dir / "pi.yaml", GainsEntry("pi", {"kp": 2e-5, "ki": 1.5e-5}, {"seed": 1}))
    write_gains(
        gains_dir / "fuzzy-pi.yaml", GainsEntry("fuzzy-pi", {"kp": 0.3, "ki": 0.05, "kx": 2e-4})
    )
    out = tmp_path / "report"
    spec = Path(__file__).resolve().parent.parent / "docs" / "examples" / "controller_pi.yaml"
    path = build_report(out, gains_dir=gains_dir, specs=[spec], **quick_options())
    assert path == out / "report.md"
    names = {p.name for p in out.iterdir()}
    for png in (
        "force_planar_E1.png",
        "force_planar_E2.png",
        "force_planar_E3.png",
        "surface.png",
        "stiffness.png",
        "latency.png",
    ):
        assert png in names
        assert (out / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert (out / png).stat().st_size < 200_000  # small enough to commit
    rrds = sorted(p.name for p in (out / "rrd").iterdir())
    assert len(rrds) == 18 and "planar_E2_fuzzy-pi_tuned.rrd" in rrds
    assert "planar_E2_fuzzy-pi_matched.rrd" in rrds
    text = path.read_text()
    for section in (
        "## Verdicts at a glance",
        "## Comparison table",
        "## The paper's claims",
        "## Verdicts per setting",
        "### Tuned against the defaults, per stiffness and latency",
        "![E1 on the planar plant](force_planar_E1.png)",
        "stiffness.png",
        "## Latency",
        "![largest stable delay against the gain factor](latency.png)",
        # the default gains are stable through the whole (quick) sweep, 8x them not even
        # without delay
        "| 1 | >= 3 | >= 3 |",
        "| 8 | 0 | 0 |",
        "| claim | gains | nominal | latency 0:0 | latency 3:3 | 1000 N/mm |",
        "## Controller specs",
    ):
        assert section in text, section
    # the spec on E1-E3 (its own axes x and z on each): 6 rows, run by the compiled loop
    spec_lines = [line for line in text.splitlines() if line.startswith(f"| `{spec}` |")]
    assert len(spec_lines) == 6 and all(line.endswith("| no | compiled |") for line in spec_lines)
    assert "| pi | tuned | 2e-05 | 1.5e-05 | - |" in text
    # measured on macvicar_whelan (1.49999 by the symmetric difference, printed to 3 digits)
    assert "the fuzzy-PI has 1.5x the PI's small-signal gain (`macvicar_whelan`: " in text
    # The nominal verdict rows are the ones assess_claims derives (the text is not canned):
    # 3 gains sets in the nominal table, matched and tuned in each of 4 conditions below.
    assert text.count("| E1: fuzzy-PI overshoots less than PI | planar |") == 3 + 2 * 4
    assert "| fuzzy-pi | matched | 0.2 | 0.05 | 0.0001333 | - | fuzzkit.studies.matching" in text
    # At 1000 N/mm both controllers trip (the stiffness study says so too): not judged.
    assert (
        "| E1: fuzzy-PI settles faster than PI | planar | matched | 1000 N/mm | not judged" in text
    )
    # What ran each run, from runs.json (the runs' own controller_impl), counted per part from
    # the quick options: 1 plant x 3 experiments x 2 controllers x 3 gains sets; 2 stiffnesses
    # x 6; 4 conditions x 3 x 2 x 2 swept gains sets; the spec on E1-E3; 2 maps x 2 x 4 runs.
    import json

    runs = json.loads((out / "runs.json").read_text())["runs"]
    counts: dict[str, int] = {}
    for r in runs:
        counts[r["part"]] = counts.get(r["part"], 0) + r.get("runs", 1)
        assert "generated" in r["controller_impl"], r
        assert "reference" not in r["controller_impl"], r
    assert counts == {
        "E1-E3": 18, "stiffness study": 12, "verdict grid": 48, "controller specs": 3,
        "latency sweep": 16,
    }  # fmt: skip
    assert "## What ran the controller" in text
    for part, n in counts.items():
        assert f"| {part} | {n} | generated " in text
    # Hand-written gains: compared with the defaults on the report's own tuning cases, each
    # case run at its latency.
    assert "carry no tuning provenance" in text
    for label in ("E1@10N/mm@lat1:1", "E3@10N/mm@lat3:3"):
        assert f"| pi | {label} |" in text and f"| fuzzy-pi | {label} |" in text


@pytest.mark.parametrize(
    ("ratios", "said"),
    [
        ((1.4999940, 1.4999940), "has 1.5x the PI's small-signal gain (`rb`: "),
        ((2.0, 0.5), "has 2x the PI's proportional and 0.5x the PI's integral small-signal gain"),
        ((1.5, 0.0), "has 1.5x the PI's proportional and no integral small-signal gain (`rb`"),
    ],
)
def test_the_default_gain_sentence_says_the_rule_bases_ratios(
    ratios: tuple[float, float], said: str
) -> None:
    assert said in default_gain_sentence("rb", ratios)


def test_report_rejects_bad_inputs(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="no such gains file"):
        build_report(tmp_path / "r", gains_dir=tmp_path, rrd=False)
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(ConfigError, match="not a folder"):
        build_report(blocker, gains_dir=tmp_path)
    with pytest.raises(ConfigError, match="unknown plant"):
        build_report(tmp_path / "r2", plants=("moon",))


def test_cli_report_bad_budget(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    from fuzzkit.cli import main

    with pytest.raises(SystemExit) as exc:
        main(["report", "--out", str(tmp_path / "r"), "--budget", "2"])
    assert exc.value.code == 2
    assert "--budget: expected an integer from 10" in capsys.readouterr().err


def test_the_conclusion_follows_from_the_verdicts() -> None:
    def c(claim: str, plant: str, gains: str, holds: bool) -> ClaimResult:
        return ClaimResult(claim, plant, gains, holds, "holds" if holds else "no", "")

    results = [
        c("A", "planar", "default", True),
        c("A", "planar", "matched", True),
        c("B", "planar", "default", False),
        c("B", "planar", "matched", False),
        c("C", "planar", "default", True),
        c("C", "planar", "matched", False),
    ]
    text = claims_conclusion(results)
    assert "Of the paper's 3 claims checked here in 2 settings, 1 holds in every setting " in text
    assert "judged (A)" in text
    assert "and 1 in none (B)." in text
    assert '"C" depends on the setting: it holds in 1 of 2 (planar/default).' in text
    assert "(the like-for-like comparison) it holds on no plant" in text
    # flipping C's matched verdict flips the sentence: the paragraph is computed, not canned
    results[-1] = c("C", "planar", "matched", True)
    assert "(A; C)" in claims_conclusion(results)


def _cr(claim: str, gains: str, condition: str, holds: bool, judged: bool = True) -> ClaimResult:
    return ClaimResult(
        claim, "arm6", gains, holds and judged, "holds" if holds else "no", "", condition, judged
    )


def test_the_conclusion_covers_latency_and_stiffness() -> None:
    """Verdicts per condition: a claim that fails only at one latency 'depends on the setting'
    and the paragraph says where; tripped settings are left out and counted."""
    conds = (NOMINAL, "latency 0:0", "latency 3:3", "1000 N/mm")
    results = []
    for gains in ("matched", "tuned"):
        for cond in conds:
            trip = cond == "1000 N/mm"
            results.append(_cr("A", gains, cond, True, judged=not trip))
            results.append(_cr("B", gains, cond, cond != "latency 3:3", judged=not trip))
    text = claims_conclusion(results)
    assert "in 8 settings" in text
    assert "1 holds in every setting judged (A)" in text
    assert (
        '"B" depends on the setting: it holds in 4 of 6 (arm6/matched except at latency 3:3;'
        in text
    )
    assert "it holds in 2 of its 3 settings" in text  # matched: nominal, 0:0 yes; 3:3 no
    assert (
        "4 verdicts are not judged because a controller tripped the safety limit (1000 N/mm)"
        in text
    )
    assert "Only PI tripped" not in text  # _cr's verdicts name nobody
    one = ClaimResult(
        "E2: x",
        "planar",
        "matched",
        False,
        "not judged (PI tripped the safety limit)",
        "",
        "50 N/mm",
        False,
    )
    assert "Only PI tripped, and fuzzy-PI held the force, in E2 planar/matched at 50 N/mm." in (
        claims_conclusion([*results, one])
    )
    summary = claims_summary(results)
    assert "- A: **holds** in every setting judged (6; 2 not judged, as a run tripped)." in summary
    # flip B at 3:3 with tuned gains: the paragraph follows
    results = [
        _cr("B", "tuned", "latency 3:3", True)
        if (r.claim, r.gains, r.condition) == ("B", "tuned", "latency 3:3")
        else r
        for r in results
    ]
    assert "arm6/tuned in every condition" in claims_conclusion(results)


def test_tripped_runs_are_not_judged_and_the_matrix_says_so() -> None:
    s = _paper_like()
    s[("planar", "E2", "pi", "default")]["tripped"] = True
    rs = assess_claims(s, "planar", "default", "1000 N/mm")
    by = {c.claim: c for c in rs}
    e2 = by["E2: PI overshoots more at the start"]
    assert not e2.judged and not e2.holds
    assert e2.verdict == "not judged (PI tripped the safety limit)"
    assert by["E1: fuzzy-PI overshoots less than PI"].judged  # E1 did not trip
    assert all(c.condition == "1000 N/mm" for c in rs)
    matrix = verdict_matrix_markdown(rs, "planar")
    assert "| claim | gains | 1000 N/mm |" in matrix
    assert "| E2: PI overshoots more at the start | default | trip (PI) |" in matrix
    assert "| E1: fuzzy-PI overshoots less than PI | default | **yes** |" in matrix


def test_conditions_list_the_nominal_once() -> None:
    conds = conditions([(0, 0), (1, 1), (3, 3)], [5.0, 10.0, 1000.0])
    assert conds == [
        Condition(NOMINAL),
        Condition("latency 0:0", latency=(0, 0)),
        Condition("latency 3:3", latency=(3, 3)),
        Condition("5 N/mm", stiffness_n_per_mm=5.0),
        Condition("1000 N/mm", stiffness_n_per_mm=1000.0),
    ]


def test_tuning_setup_is_read_back_from_a_gains_file() -> None:
    fallback = TuningSetup()
    prov = {
        "experiments": ["E1", "E2"],
        "plant": "planar",
        "stiffness_n_per_mm": [5.0, 20.0],
        "latency_periods": [[0, 0], [3, 3]],
    }
    assert setup_from_provenance({**prov, "admit": "experiment"}, fallback) == TuningSetup(
        ("E1", "E2"), "planar", (5.0, 20.0), ((0, 0), (3, 3)), "experiment"
    )
    assert setup_from_provenance(prov, fallback).admit == "case"  # before the rule was saved
    # written before latencies were recorded: tuned at the experiments' own, 1 + 1
    old = {**prov, "latency_periods": "as defined"}
    assert setup_from_provenance(old, fallback).latencies == ((1, 1),)
    assert setup_from_provenance({"seed": 1}, fallback) is fallback


def test_the_report_tunes_both_controllers_on_one_problem(tmp_path: Path) -> None:
    """Protocol (b): PI and fuzzy-PI tuned for the same cost on the same cases (stiffness x
    latency), said in each gains file; the per-case prices of the report agree with the
    Python loop's (an independent implementation of the closed loop)."""
    from fuzzkit.control.gains import read_gains_file
    from fuzzkit.loop.python_loop import run
    from fuzzkit.report.build import CONTROLLERS
    from fuzzkit.report.tuned import gains_for, tuned_vs_default
    from fuzzkit.studies.experiments import DEFAULT_GAINS, experiment, with_stiffness
    from fuzzkit.studies.tuning import TUNING_HORIZON_S, run_cost

    setup = TuningSetup(("E1",), "arm6", (20.0,), ((0, 0), (3, 3)))
    got = {
        c: gains_for(c, None, tmp_path, setup, 10, "macvicar_whelan", 0, 1, None)
        for c in CONTROLLERS
    }
    provs = [got[c][1] for c in CONTROLLERS]
    for key in ("experiments", "plant", "stiffness_n_per_mm", "latency_periods", "admit"):
        assert provs[0][key] == provs[1][key], key
    assert provs[0]["latency_periods"] == [[0, 0], [3, 3]]
    for c in CONTROLLERS:
        entry = read_gains_file(tmp_path / "gains" / f"{c}.yaml")[c]
        assert setup_from_provenance(entry.provenance, TuningSetup()) == setup
    cases = tuned_vs_default(setup, "pi", "macvicar_whelan", got["pi"][0])
    assert [c.latency for c in cases] == [(0, 0), (3, 3)]
    exp = with_stiffness(experiment("E1"), 20e3)
    for c in cases:
        assert c.latency is not None
        reference = run(
            exp,
            "arm6",
            "pi",
            gains=DEFAULT_GAINS["pi"],
            latency=c.latency,
            duration_s=TUNING_HORIZON_S["E1"],
        )
        assert c.default_cost == pytest.approx(run_cost(reference), rel=1e-6)


def test_a_rule_base_without_small_signal_gain_runs_its_defaults_as_matched_and_says_so() -> None:
    """``sugeno_pi`` holds du = 0 around the origin: F(e, 0) = 0.2 e^2 near it (a hand
    derivation: only the Z and P terms of e fire, Z x Z concludes 0 and P x Z 0.2 e), so its
    slopes there are 0 and there is no small-signal gain to match. The report's "matched"
    fuzzy-PI then runs the default gains and the report says why."""
    from fuzzkit.loop.python_loop import load_surface
    from fuzzkit.report.build import matched_gains_for_report
    from fuzzkit.studies.experiments import DEFAULT_GAINS

    surface = load_surface("sugeno_pi")
    assert surface(0.1, 0.0) == pytest.approx(0.2 * 0.1**2, rel=1e-9)  # the derivation above
    gains, note = matched_gains_for_report(surface, "sugeno_pi")
    assert gains == DEFAULT_GAINS["fuzzy-pi"]
    assert note is not None and "`sugeno_pi` has no small-signal gain" in note
    assert "runs the default gains" in note
    gains, note = matched_gains_for_report(load_surface("macvicar_whelan"), "macvicar_whelan")
    assert note is None and gains["kx"] != DEFAULT_GAINS["fuzzy-pi"]["kx"]  # slopes 1.5: matched
