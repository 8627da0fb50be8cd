"""The certificate's task is a scenario (issue 28 item 6): ``fuzzkit scenario regulate`` prints
it, ``fuzzkit simulate regulate`` runs it, and ``stability --simulate`` runs exactly it."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from fuzzkit.analysis.regulation import regulation_experiment
from fuzzkit.analysis.simulated import SimCase, outcome, run_case
from fuzzkit.cli import main
from fuzzkit.studies.regulation import APPROACH_S, approach_speed
from fuzzkit.studies.scenario_file import load_scenario


def test_scenario_lists_and_prints_regulate(capsys, tmp_path: Path):
    assert main(["scenario"]) == 0
    assert "regulate  guarded approach" in capsys.readouterr().out
    assert main(["scenario", "regulate"]) == 0
    text = capsys.readouterr().out
    (tmp_path / "r.yaml").write_text(text)
    # the printed file is the task the certificate is checked against, field for field
    assert load_scenario(tmp_path / "r.yaml") == regulation_experiment()


@pytest.mark.parametrize("stiffness", [5e3, 2e4, 1e6])
def test_the_approach_follows_the_stiffness_and_touches_after_0_1_s(stiffness):
    exp = regulation_experiment(stiffness)
    (start, end) = exp.scenario.path
    speed = (start.z - end.z) / (end.t_s - start.t_s)
    assert speed == pytest.approx(approach_speed(stiffness, 25.0, 10.0))
    assert exp.scenario.contact.stiffness_n_per_m == stiffness
    # the tool's surface reaches the table after APPROACH_S
    gap = start.z - (-0.3 + exp.scenario.tool.radius_m)
    assert gap / speed == pytest.approx(APPROACH_S)
    # the impact over a 0.1 s reaction stays within 1/5 of the 15 N headroom
    assert stiffness * speed * 0.1 <= 0.2 * 15.0 + 1e-9


@pytest.mark.slow
@pytest.mark.parametrize(
    ("controller", "stiffness", "latency"), [("pi", 50.0, (1, 1)), ("fuzzy-pi", 200.0, (0, 0))]
)
def test_a_stability_cell_is_the_run_of_fuzzkit_simulate_regulate(
    capsys, controller, stiffness, latency
):
    case = SimCase(regulation_experiment(), "arm6", controller, (), stiffness, latency, seed=2)
    result = run_case(case)
    argv = ["simulate", "regulate", "--plant", "arm6", "--controller", controller]
    argv += ["--stiffness", f"{stiffness:g}", "--latency", f"{latency[0]},{latency[1]}"]
    argv += ["--seed", "2", "--json"]
    assert main(argv) == 0
    data = json.loads(capsys.readouterr().out)
    z = data["axes"]["z"]
    assert data["tripped"] == result.tripped
    assert z["peak_force_true"] == pytest.approx(float(np.max(result.force_true[:, 2])), abs=1e-9)
    assert z["first_contact_s"] == pytest.approx(APPROACH_S, abs=0.05)
    # and the stability command's own simulated outcome is this run's
    assert (
        main(
            [
                "stability",
                "regulate",
                "--controller",
                controller,
                "--plant",
                "arm6",
                "--stiffness",
                f"{stiffness:g}",
                "--latency",
                f"{latency[0]}:{latency[1]}",
                "--simulate",
                "--workers",
                "1",
                "--json",
            ]
        )
        == 0
    )
    cell = json.loads(capsys.readouterr().out)["cells"][0]
    seed0 = run_case(SimCase(regulation_experiment(), "arm6", controller, (), stiffness, latency))
    assert cell["simulated"] == outcome(seed0)
