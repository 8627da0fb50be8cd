"""``fuzzkit stability --spec`` certifies the spec as it ships (issue 28 items 3 and 4): its
gains, set point, low-pass, limits, surface method and input roles reach the certificate, and
user-style rule bases are certified or refused with the reason."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from fuzzkit.analysis.loop_model import AxisLoop, closed_loop_matrix
from fuzzkit.cli import main

USER = Path(__file__).parent / "data" / "user"
GRID = ["--plant", "arm6", "--stiffness", "5,10,20,50", "--latency", "0:0,1:1,2:2"]


def _run(capsys, *argv: str) -> dict:
    assert main(["stability", "regulate", *argv, *GRID, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def _variant(tmp_path: Path, name: str, old: str, new: str) -> str:
    text = (USER / "spec_renamed.yaml").read_text()
    assert old in text
    path = tmp_path / name
    path.write_text(text.replace(old, new))
    (tmp_path / "renamed.yaml").write_text((USER / "renamed.yaml").read_text())
    return str(path)


def _verdicts(data: dict) -> list[bool]:
    return [c["certified"] for c in data["cells"]]


def test_the_spec_as_shipped_reaches_the_certificate(capsys):
    data = _run(capsys, "--spec", str(USER / "spec_renamed.yaml"))
    model = data["model"]
    assert model["deployed"]["spec"] == "user_renamed" and model["deployed"]["axis"] == "z"
    assert model["frontend_lowpass_hz"] == 40.0
    assert model["limits_m"] == {"step_m": 0.001, "correction_m": 0.05}
    assert model["gains"]["kx"] == 0.0002
    # the renamed inputs (err, derr) in role order: the PI-like structure is found
    assert model["fuzzy"]["bounds"] == "phi"
    assert model["fuzzy"]["surface_method"] == "exact"
    assert model["equilibrium"]["at_setpoint"] is True
    assert any(_verdicts(data)) and not all(_verdicts(data))


@pytest.mark.parametrize(
    ("old", "new"),
    [
        (
            "z:\n    setpoint_n: 10.0\n    gains: {kp: 0.2, ki: 0.05, kx: 0.0002}",
            "z:\n    setpoint_n: 10.0\n    gains: {kp: 0.2, ki: 0.05, kx: 0.0008}",
        ),
        ("lowpass_hz: 40.0", "lowpass_hz: 1.0"),
    ],
)
def test_changing_the_specs_gains_or_low_pass_changes_verdicts(capsys, tmp_path, old, new):
    base = _verdicts(_run(capsys, "--spec", str(USER / "spec_renamed.yaml")))
    changed = _verdicts(_run(capsys, "--spec", _variant(tmp_path, "s.yaml", old, new)))
    assert changed != base
    assert sum(changed) < sum(base)  # a 4x loop gain, a 40x slower filter: fewer certified


def test_the_front_end_filter_is_in_the_loop_model():
    # closed forms of the extra state (the last): v[k+1] = b2 v[k] + (1 - b2) y[k+1], and the
    # law reads v instead of the sample
    loop = AxisLoop(
        period_s=0.004,
        stiffness_n_per_m=1e4,
        damping_n_s_per_m=50.0,
        sensor_delay=0,
        command_delay=0,
        filter_cutoff_hz=60.0,
        kp=4e-5,
        ki=1e-5,
        frontend_cutoff_hz=40.0,
    )
    assert loop.order == 5
    a = closed_loop_matrix(loop, 1.0, 1.0, 0.6, 1.0)
    beta = math.exp(-2 * math.pi * 60.0 * 0.004)
    b2 = math.exp(-2 * math.pi * 40.0 * 0.004)
    w = np.zeros(5)
    w[2] = 1.0  # only the sensor filter's state: y[k+1] = beta
    assert (a @ w)[4] == pytest.approx((1 - b2) * beta)
    v = np.zeros(5)
    v[4] = 1.0  # only the front end's state: v[k+1] = b2, u[k+1] = -(Kp + Ki) k b2 + Kp k
    assert (a @ v)[4] == pytest.approx(b2)
    assert (a @ v)[3] == pytest.approx(-(4e-5 + 1e-5) * 1e4 * b2 + 4e-5 * 1e4)


def test_spec_and_controller_options_do_not_mix(capsys):
    argv = ["stability", "regulate", "--spec", str(USER / "spec_renamed.yaml")]
    argv += ["--controller", "pi", "--stiffness", "10", "--latency", "1:1"]
    assert main(argv) == 2
    assert "--controller cannot be used with it" in capsys.readouterr().err


def test_without_spec_it_says_which_controller_it_assumed(capsys):
    assert main(["stability", "regulate", "--stiffness", "10", "--latency", "1:1"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("assumed controller: pi (kp=4e-05, ki=1e-05)")
    assert "give --spec SPEC" in out


@pytest.mark.parametrize(
    ("spec", "outcome"),
    [
        ("spec_renamed.yaml", "certified"),
        # a dead band around zero error: the loop rests anywhere in it, refused with why
        ("spec_gauss_prod.yaml", "rest"),
        # non-monotone far from the origin: certified on a box around the rest point only
        ("spec_nonuniform5.yaml", "local"),
        # a negative slope at the origin of its surface: no box gets stable vertices
        ("spec_user_pi.yaml", "lyapunov"),
    ],
)
def test_user_style_specs_are_certified_or_refused_with_the_reason(capsys, spec, outcome):
    data = _run(capsys, "--spec", str(USER / spec))
    cells = data["cells"]
    if outcome in ("certified", "local"):
        assert any(c["certified"] for c in cells)
        if outcome == "local":
            boxes = [c["fuzzy_region_scaled"] for c in cells if c["certified"]]
            assert all(b < 0.2 for b in boxes)
        return
    assert not any(c["certified"] for c in cells)
    for c in cells:
        assert c["why_not_certified"]
        if outcome == "rest":
            assert "not the loop's rest point" in c["why_not_certified"]
    if outcome == "rest":
        assert "can rest anywhere" in data["model"]["equilibrium"]["why"]


def test_local_certificates_of_a_user_rule_base_settle_in_simulation(capsys):
    # issue 40 item 6: the whole-square slopes of nonuniform5 refuse every cell; the boxes
    # around the rest point certify some, and each of those settles (no false certificate)
    argv = ["stability", "regulate", "--spec", str(USER / "spec_nonuniform5.yaml")]
    argv += ["--plant", "arm6", "--stiffness", "2,5,10", "--latency", "0:0,1:1"]
    assert main([*argv, "--simulate", "--json"]) == 0
    cells = json.loads(capsys.readouterr().out)["cells"]
    certified = [c for c in cells if c["certified"]]
    assert len(certified) >= 3
    assert all(c["simulated"] == "settled" for c in certified)
    assert all(0.0 < c["region_n"] < 1.0 for c in certified)  # local: well under 1 N
    # each cell names what ran it: the spec's own generated controller, never the reference
    assert all("user_nonuniform5" in c["controller_impl"] for c in cells), cells[0]
    assert not any("reference" in c["controller_impl"] for c in cells)
