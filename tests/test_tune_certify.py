"""``fuzzkit tune --certify``: only gain sets the constraint accepts are simulated or returned."""

from __future__ import annotations

from pathlib import Path

import pytest

from fuzzkit.analysis.region import CertifiedOver
from fuzzkit.cli import main
from fuzzkit.studies.experiments import experiment
from fuzzkit.studies.tuning import tune

pytestmark = pytest.mark.slow


def test_the_search_simulates_and_returns_only_accepted_gain_sets():
    seen: list[float] = []

    def constraint(g):
        ok = g["kp"] <= 2.0e-5  # the default kp is 4e-5: the baseline itself is refused
        seen.append(g["kp"])
        return ok

    r = tune(
        ["E1"],
        "pi",
        plant="arm6",
        stiffnesses_n_per_mm=[10.0],
        budget=12,
        workers=1,
        constraint=constraint,
    )
    assert any(k > 2.0e-5 for k in seen)  # the constraint had something to refuse
    # the defaults come back only when no accepted candidate beat them (the CLI then refuses)
    assert r.gains["kp"] <= 2.0e-5 or (r.kept_defaults and r.gains["kp"] == pytest.approx(4e-5))


def test_certified_over_agrees_with_the_region():
    pred = CertifiedOver(experiment("E1"), "pi", "arm6", (10.0, 100.0), ((1, 1),))
    assert not pred({})  # default PI at 100 N/mm, 1+1: refused (and trips in simulation)
    assert CertifiedOver(experiment("E1"), "pi", "arm6", (10.0,), ((1, 1),))({})


def _tune_certified(out: Path, budget: str, certify: str, latency: str) -> int:
    return main(
        [
            "tune",
            "E1",
            "--controller",
            "pi",
            "--plant",
            "arm6",
            "--stiffness",
            "10",
            "--budget",
            budget,
            "--workers",
            "1",
            "--quiet",
            "--certify",
            certify,
            "--certify-latency",
            latency,
            "--out",
            str(out),
        ]
    )


def test_cli_tune_certify_says_so_and_the_result_is_certified(tmp_path: Path, capsys):
    out = tmp_path / "g.yaml"
    code = _tune_certified(out, "12", "10,20", "1:1")
    text = capsys.readouterr().out
    assert code == 0
    assert "certified stable at 10/20 N/mm" in text
    from fuzzkit.control.gains import read_gains

    gains = read_gains(str(out), "pi")
    assert CertifiedOver(experiment("E1"), "pi", "arm6", (10.0, 20.0), ((1, 1),))(gains)


def test_cli_tune_certify_refuses_to_write_uncertified_gains(tmp_path: Path, capsys):
    out = tmp_path / "g.yaml"
    code = _tune_certified(out, "10", "1000", "4:4")
    captured = capsys.readouterr()
    pred = CertifiedOver(experiment("E1"), "pi", "arm6", (1000.0,), ((4, 4),))
    assert not pred({})  # the defaults are not certified there
    if code == 1:  # no certified candidate beat the defaults: nothing written, and it says so
        assert "no certified gains" in captured.err
        assert not out.exists()
    else:  # a certified candidate was found: what was written is certified
        assert code == 0
        from fuzzkit.control.gains import read_gains

        assert pred(read_gains(str(out), "pi"))


def test_cli_tune_certify_writes_nothing_when_no_gain_set_is_certified(
    tmp_path: Path, capsys, monkeypatch: pytest.MonkeyPatch
):
    # the refusal path, made certain: a certificate that holds for no gain set at all
    from fuzzkit.analysis import region

    monkeypatch.setattr(region.CertifiedOver, "__call__", lambda self, gains: False)
    out = tmp_path / "g.yaml"
    code = _tune_certified(out, "10", "10", "1:1")
    captured = capsys.readouterr()
    assert code == 1
    assert "no certified gains" in captured.err
    assert not out.exists() and list(tmp_path.iterdir()) == []
