"""A poor fit of the inner loop is a warning that names the fit error (issue 40 item 5)."""

from __future__ import annotations

import dataclasses

import pytest

from fuzzkit.analysis import region as region_module
from fuzzkit.analysis.inner_loop import POOR_FIT_NRMSE, identify, poor_fit
from fuzzkit.cli import main

ARGV = ["stability", "regulate", "--plant", "arm6", "--stiffness", "10", "--latency", "0:0"]


def test_the_warning_names_the_fit_error_above_the_threshold() -> None:
    assert POOR_FIT_NRMSE == 0.10
    assert poor_fit("arm6", 0.0001) is None and poor_fit("arm6", 0.10) is None
    message = poor_fit("mujoco", 0.955)
    assert message is not None and "mujoco" in message and "95.5 %" in message


def test_stability_warns_on_a_poor_fit_and_not_on_a_good_one(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(ARGV) == 0
    assert "warning" not in capsys.readouterr().err  # arm6 fits to about 0.01 %
    good = identify("arm6")
    bad = dataclasses.replace(
        good, fits=tuple(dataclasses.replace(f, nrmse=0.5) for f in good.fits)
    )
    monkeypatch.setattr(region_module, "identify", lambda plant: bad)
    assert main([*ARGV, "--json"]) == 0
    err = capsys.readouterr().err
    assert "fuzzkit: warning: the inner loop's model fits arm6 with a fit error of 50 %" in err


@pytest.mark.verify
def test_mujoco_warns_with_its_fit_error(capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["stability", "regulate", "--plant", "mujoco", "--stiffness", "10", "--latency", "0:0"]
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert "fits mujoco with a fit error of" in err
