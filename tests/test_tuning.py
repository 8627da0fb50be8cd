"""Optimal gains: against a dense grid search on a simple plant, against the defaults on the real
planar plant, determinism, Ctrl-C, and the gains file (round trip and bad files)."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from fuzzkit.control.controllers import saturated_sum_surface
from fuzzkit.control.gains import GainsEntry, parse_gains, read_gains, read_gains_file, write_gains
from fuzzkit.errors import ConfigError
from fuzzkit.loop.python_loop import run
from fuzzkit.plants.contact import ToolModel
from fuzzkit.plants.contract import PlantSample, Scenario
from fuzzkit.plants.environment import Table, Waypoint, nominal_position
from fuzzkit.studies.experiments import Experiment, experiment, with_stiffness
from fuzzkit.studies.tuning import (
    TUNING_HORIZON_S,
    GainSpace,
    Progress,
    TuneResult,
    TuningProblem,
    evaluate_gains,
    optimise,
    run_cost,
    tune,
)

# --------------------------------------------------------------------------------------------
# A simple plant with a cheap closed loop: first-order position servo, linear spring contact
# --------------------------------------------------------------------------------------------

TABLE_Z = -0.30


class SpringPlant:
    """Tool tip follows its target with a 20 ms first-order lag; a table below is a spring.

    Exact and noise-free: force = k * penetration. Independent of fuzzkit.planar_sim and motion.
    """

    name = "spring"

    def __init__(self) -> None:
        self._period = 0.004

    @property
    def period_s(self) -> float:
        return self._period

    def reset(self, scenario: Scenario, seed: int = 0) -> PlantSample:
        self.scn = scenario
        self._period = scenario.period_s
        self.t = 0.0
        self.pos = nominal_position(scenario.path, 0.0)
        return self._sample(self.pos.copy())

    def step(self, correction_xyz: np.ndarray, path_time_s: float) -> PlantSample:
        nominal = nominal_position(self.scn.path, path_time_s)
        target = nominal + correction_xyz
        self.pos = self.pos + (1.0 - math.exp(-self._period / 0.02)) * (target - self.pos)
        self.t += self._period
        return self._sample(target)

    def _sample(self, target: np.ndarray) -> PlantSample:
        depth = TABLE_Z - (self.pos[2] - self.scn.tool.radius_m)
        k = self.scn.contact.stiffness_n_per_m
        f_base = np.array([0.0, 0.0, -k * depth]) if depth > 0.0 else np.zeros(3)
        f_task = self.scn.rotation.T @ f_base
        return PlantSample(
            t_s=self.t,
            force=f_task,
            force_true=f_task.copy(),
            tool_position=self.pos.copy(),
            nominal_position=nominal_position(self.scn.path, 0.0),
            target_position=target,
            joint_angles=np.zeros(2),
            in_contact=bool(depth > 0.0),
            contact_points=np.zeros((0, 3)),
            arm_points=np.zeros((2, 3)),
        )


def press_on_spring(horizon_s: float = 1.0) -> Experiment:
    """Press 10 N on the table from 0.5 mm above it, force loop active from the start."""
    tool = ToolModel(length_m=0.1, radius_m=0.02)
    z = TABLE_Z + tool.radius_m + 0.0005
    scn = Scenario(
        name="spring",
        path=(Waypoint(0.0, 0.4, 0.0, z),),
        objects=(Table(TABLE_Z),),
        duration_s=horizon_s,
        tool=tool,
    )
    return Experiment(
        name="spring",
        title="press 10 N on a spring table",
        scenario=scn,
        setpoints=(0.0, 0.0, 10.0),
        selection=(False, False, True),
        force_limit_n=50.0,
        engage_threshold_n=None,
        # an ideal interface: these tests are about the optimiser (tests/test_latency.py is
        # about latency), and with delay this box's optimum lies on a narrow ridge
        latency_periods=(0, 0),
    )


#: A 2-decade box around the spring plant's good region (loop gain Ki*k from 0.01 to 1).
SPRING_SPACE = GainSpace(("kp", "ki"), (1.0e-6, 1.0e-6), (1.0e-4, 1.0e-4))


def _spring_problem(
    controller: str = "pi", space: GainSpace | None = SPRING_SPACE
) -> TuningProblem:
    return TuningProblem.build(
        [press_on_spring()],
        controller,
        rulebase=saturated_sum_surface,
        plant=SpringPlant,
        stiffnesses_n_per_mm=(10.0,),
        space=space,
    )


@pytest.mark.verify  # 686 closed-loop runs of the spring plant: the deep check of the optimiser
def test_tuning_is_within_a_few_percent_of_a_dense_grid_search() -> None:
    problem = _spring_problem()
    lo, hi = SPRING_SPACE.log_bounds
    n = 25
    grid = [
        problem.aggregate(evaluate_gains(problem, {"kp": 10.0**a, "ki": 10.0**b}))
        for a in np.linspace(lo[0], hi[0], n)
        for b in np.linspace(lo[1], hi[1], n)
    ]
    best = min(grid)
    # The landscape has a real optimum: most of the box is much worse than its best.
    assert float(np.median(grid)) > 1.5 * best
    result = optimise(problem, budget=60, seed=1, workers=1)
    assert result.cost <= 1.03 * best, (result.cost, best)
    # The reported cost is what an independent evaluation of the returned gains gives.
    again = problem.aggregate(evaluate_gains(problem, result.gains))
    assert again == pytest.approx(result.cost, rel=1e-12)


def test_fuzzy_pi_tuning_on_the_spring_plant_beats_the_defaults() -> None:
    problem = _spring_problem("fuzzy-pi", space=None)
    result = optimise(problem, budget=30, seed=0, workers=1)
    assert set(result.gains) >= {"kp", "ki", "kx", "u_min", "u_max"}
    assert result.cost < result.baseline_cost
    lo, hi = problem.space.log_bounds
    x = np.log10([result.gains[k] for k in problem.space.names])
    assert np.all(x >= lo - 1e-9) and np.all(x <= hi + 1e-9)


def test_tuned_gains_no_worse_than_defaults_on_every_experiment() -> None:
    """Tuned jointly on E1-E3 (planar plant, tiny budget), checked per experiment by re-running
    each experiment independently of the optimiser."""
    names = ("E1", "E2", "E3")
    result = tune(names, "pi", stiffnesses_n_per_mm=(10.0,), budget=10, seed=0, workers=2)
    assert result.evaluations == 10
    for name in names:
        exp = with_stiffness(experiment(name), 1.0e4)
        h = TUNING_HORIZON_S[name]
        tuned = run_cost(run(exp, "planar", "pi", gains=result.gains, duration_s=h))
        default = run_cost(run(exp, "planar", "pi", gains=result.baseline_gains, duration_s=h))
        assert tuned <= default + 1e-12, (name, tuned, default)
        assert tuned == pytest.approx(result.experiment_costs[name], rel=1e-9)


def test_same_seed_same_gains_for_any_number_of_workers() -> None:
    problem = _spring_problem()
    a = optimise(problem, budget=20, seed=3, workers=1)
    b = optimise(problem, budget=20, seed=3, workers=1)
    c = optimise(problem, budget=20, seed=3, workers=2)
    assert a.gains == b.gains == c.gains
    assert a.history == c.history


@pytest.mark.parametrize("workers", [1, 2])
def test_ctrl_c_keeps_the_best_so_far(workers: int) -> None:
    seen: list[Progress] = []

    def stop_after_three(p: Progress) -> None:
        seen.append(p)
        if len(seen) == 3:
            raise KeyboardInterrupt

    problem = _spring_problem()
    result = optimise(problem, budget=60, seed=0, workers=workers, callback=stop_after_three)
    assert result.interrupted
    assert result.evaluations == seen[-1].evaluations < 60
    assert result.cost == seen[-1].best_cost  # one experiment: the best is eligible
    assert result.cost <= result.baseline_cost
    again = problem.aggregate(evaluate_gains(problem, result.gains))
    assert again == pytest.approx(result.cost, rel=1e-12)


def test_cost_prefers_good_gains_and_prices_a_missed_contact() -> None:
    exp = press_on_spring()
    good = run_cost(run(exp, SpringPlant(), "pi", gains={"kp": 1e-5, "ki": 1e-5}))
    sluggish = run_cost(run(exp, SpringPlant(), "pi", gains={"kp": 1e-5, "ki": 3e-8}))
    ringing = run_cost(run(exp, SpringPlant(), "pi", gains={"kp": 0.0, "ki": 8e-5}))
    assert good < sluggish and good < ringing
    # Never touching (the set point is 0 N everywhere: the loop does not move): priced w_none.
    idle = Experiment(
        name="idle",
        title="",
        scenario=exp.scenario,
        setpoints=(0.0, 0.0, 0.0),
        selection=(False, False, True),
        force_limit_n=50.0,
        engage_threshold_n=None,
    )
    assert run_cost(run(idle, SpringPlant(), "pi")) == 10.0


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"controller": "pid"}, "unknown controller"),
        ({"experiments": ["E9"]}, "unknown experiment"),
        ({"experiments": []}, "at least one experiment"),
        ({"stiffnesses_n_per_mm": (10.0, -1.0)}, "positive finite"),
        ({"plant": "moon"}, "unknown plant"),
        ({"budget": 5}, "budget must be >= 10"),
        ({"workers": 0}, "workers must be >= 1"),
    ],
)
def test_bad_tuning_arguments(kwargs: dict[str, object], match: str) -> None:
    args: dict[str, object] = {"experiments": ["E1"], "controller": "pi", "budget": 10}
    args.update(kwargs)
    with pytest.raises(ConfigError, match=match):
        tune(**args)  # type: ignore[arg-type]


# --------------------------------------------------------------------------------------------
# Gains files
# --------------------------------------------------------------------------------------------


def test_gains_file_round_trip_and_merge(tmp_path: Path) -> None:
    path = tmp_path / "g.yaml"
    fuzzy = {"kp": 0.1261914688960387, "ki": 0.049999999999999996, "kx": 2.0000000000000004e-4}
    write_gains(path, GainsEntry("fuzzy-pi", fuzzy, {"seed": 0, "experiments": ["E1"]}))
    _, kept = write_gains(path, GainsEntry("pi", {"kp": 3e-5, "ki": 1.1e-5}))
    assert kept == ["fuzzy-pi"]
    assert read_gains(path, "fuzzy-pi") == fuzzy  # exact floats
    assert read_gains(path, "pi") == {"kp": 3e-5, "ki": 1.1e-5}
    entries = read_gains_file(path)
    assert entries["fuzzy-pi"].provenance == {"seed": 0, "experiments": ["E1"]}
    _, kept = write_gains(path, GainsEntry("pi", {"kp": 1e-5, "ki": 1e-5}), merge=False)
    assert kept == [] and read_gains(path, "fuzzy-pi") == {}
    assert read_gains(None, "pi") == {}


@pytest.mark.parametrize(
    "text, match",
    [
        ("pi:\n  gains:\n    kp: -1\n", "g.yaml:3:5: gain kp must be >= 0"),
        ("fuzzy-pi:\n  gains: {kp: 0.1, ki: 0, kx: 1e-4}\n", "g.yaml:2:20: gain ki must be > 0"),
        ("pi:\n  gains:\n    kp: 1e-5\n    kd: 2\n", "g.yaml:4:5: unknown gain 'kd' for pi"),
        ("pi:\n  gains: {kp: 1e-5}\n  notes: x\n", "g.yaml:3:3: unknown key 'notes' in the pi"),
        ("pi:\n  gains: {kp: 1e-5}\n  provenance: [1]\n", "provenance must be a mapping"),
        ("pi:\n  gains: [1, 2]\n", "gains must be a mapping"),
        ("kp: .nan\n", "g.yaml:1:1: gain kp must be a finite number"),
        ("pi: {u_min: 0.1}\n", "u_min must be <= 0"),
        ("", "g.yaml:1:1: file is empty"),
        ("pi: {kp: [1\n", "g.yaml:2:1: invalid YAML"),
        ("pid: {kp: 1}\npi: {kp: 1e-5}\n", "g.yaml:1:1: unknown controller keys ['pid']"),
        ("pi: {kp: 1e-5, kp: 2e-5}\n", "g.yaml:1:16: duplicate key 'kp' (first defined on line 1)"),
        ("pi: {yes: 1e-5}\n", "g.yaml:1:6: expected a name as key, got yes (YAML reads"),
        ("pi: {kp: 1" + "0" * 400 + "}\n", "g.yaml:1:10: integer of 401 digits for a number"),
        ("pi: {kp: 1e-5}\x07\n", "g.yaml:1:15: control character U+0007"),
        ("pi: {kp: 0x1" + "0" * 300 + "}\n", "g.yaml:1:10: integer of 302 digits for a number"),
    ],
)
def test_bad_gains_files(tmp_path: Path, text: str, match: str) -> None:
    path = tmp_path / "g.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError) as info:
        read_gains(path, "pi" if "fuzzy" not in text else "fuzzy-pi")
    assert match in str(info.value)


def test_every_problem_of_a_gains_file_is_listed() -> None:
    with pytest.raises(ConfigError) as info:
        parse_gains("pi:\n  kp: -1\n  ki: fast\n  kd: 1\n", "g.yaml")
    msg = str(info.value)
    assert "g.yaml:2:3: gain kp" in msg and "g.yaml:3:3: gain ki" in msg
    assert "g.yaml:4:3: unknown" in msg


def test_flat_file_with_a_key_the_controller_lacks(tmp_path: Path) -> None:
    path = tmp_path / "g.yaml"
    path.write_text("kp: 0.2\nki: 0.05\nkx: 1e-4\n")
    assert read_gains(path, "fuzzy-pi") == {"kp": 0.2, "ki": 0.05, "kx": 1e-4}
    with pytest.raises(ConfigError, match="unknown gain 'kx' for pi"):
        read_gains(path, "pi")


# --------------------------------------------------------------------------------------------
# CLI
# --------------------------------------------------------------------------------------------


def test_cli_tune_writes_a_file_simulate_accepts(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from fuzzkit.cli import main

    out = tmp_path / "gains.yaml"
    args = ["tune", "E1", "--controller", "pi", "--budget", "10", "--workers", "1"]
    assert main([*args, "--stiffness", "10", "--quiet", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "vs the default gains" in text and f"wrote {out}" in text
    entry = read_gains_file(out)["pi"]
    assert entry.provenance["experiments"] == ["E1"] and entry.provenance["budget"] == 10
    assert entry.provenance["cost"] <= entry.provenance["default_cost"]
    assert main(["simulate", "E1", "--controller", "pi", "--gains", str(out), "--json"]) == 0
    # what ran the candidates, as simulate's runs name it: the generated controller
    ran = json.loads(capsys.readouterr().out)
    said = f"{ran['controller_impl']} [{ran['loop']}]"
    assert f"controller: {said}\n" in text and entry.provenance["controller_impl"] == said
    assert "generated C controller" in said or "generated Python" in said


def test_cli_tune_ctrl_c_writes_the_best_so_far(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    from fuzzkit.cli import main
    from fuzzkit.studies import tuning

    calls = []

    def interrupt(p: Progress) -> None:
        calls.append(p)
        if len(calls) == 2:
            raise KeyboardInterrupt

    monkeypatch.setattr(tuning, "progress_callback", lambda bar: interrupt)
    out = tmp_path / "gains.yaml"
    args = ["tune", "E1", "--controller", "pi", "--budget", "40", "--workers", "1"]
    assert main([*args, "--stiffness", "10", "--out", str(out)]) == 130
    captured = capsys.readouterr()
    assert "interrupted: best so far" in captured.out
    said = captured.err.strip().splitlines()
    # the honest-tuning warnings about the best so far may come first; the interrupt note last
    assert said[-1:] == [f"fuzzkit: interrupted (Ctrl-C); {out} holds the best gains so far"]
    assert all(ln.startswith("warning: ") for ln in said[:-1]), said
    prov = read_gains_file(out)["pi"].provenance
    assert prov["interrupted"] is True and prov["evaluations"] < 40


@pytest.mark.parametrize(
    "extra, match",
    [
        (["--stiffness", "10,abc"], "got 'abc'"),
        (["--stiffness", "0"], "expected a stiffness > 0"),
        (["--budget", "3"], "--budget: expected an integer from 10"),
        (["--out", "/nonexistent/dir/g.yaml"], "does not exist"),
        (["--plant", "planar", "--rulebase", "no_such_rb"], "no_such_rb"),
    ],
)
def test_cli_tune_bad_arguments(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], extra: list[str], match: str
) -> None:
    from fuzzkit.cli import main

    args = ["tune", "E1", "--out", str(tmp_path / "g.yaml"), "--workers", "1", *extra]
    try:
        code = main(args)
    except SystemExit as exc:  # a value argparse refuses (--stiffness)
        code = exc.code
    assert code == 2
    err = capsys.readouterr().err
    assert match in err and "Traceback" not in err
    assert not (tmp_path / "g.yaml").exists()


# --------------------------------------------------------------------------------------------
# Admission per case, progress, and what the command says
# --------------------------------------------------------------------------------------------


def _two_stiffness_problem() -> TuningProblem:
    return TuningProblem.build(
        [press_on_spring()],
        "pi",
        rulebase=saturated_sum_surface,
        plant=SpringPlant,
        stiffnesses_n_per_mm=(5.0, 40.0),
        space=SPRING_SPACE,
    )


def test_tuned_gains_no_worse_than_defaults_on_every_stiffness() -> None:
    problem = _two_stiffness_problem()
    seen: list[Progress] = []
    result = optimise(problem, budget=24, seed=2, workers=1, callback=seen.append)
    tuned = evaluate_gains(problem, result.gains)  # priced again, outside the optimiser
    default = evaluate_gains(problem, result.baseline_gains)
    assert len(tuned) == 2
    for t, d in zip(tuned, default, strict=True):
        assert t <= d + 1e-12
    # The progress shows the cost of what would be saved, never a refused candidate's.
    assert seen[-1].best_cost == pytest.approx(result.cost, rel=1e-12)
    assert all(p.best_cost <= p.baseline_cost + 1e-12 for p in seen)
    assert all(p.cheapest_cost <= p.best_cost + 1e-12 for p in seen)


def test_experiment_rule_may_trade_one_stiffness_for_another() -> None:
    problem = _two_stiffness_problem()
    per_case = optimise(problem, budget=24, seed=2, workers=1)
    per_exp = optimise(problem, budget=24, seed=2, workers=1, admit="experiment")
    assert per_exp.admit == "experiment" and per_case.admit == "case"
    # The looser rule admits everything the strict one does: never a dearer result.
    assert per_exp.cost <= per_case.cost + 1e-12
    with pytest.raises(ConfigError, match="unknown admission rule"):
        optimise(problem, budget=10, workers=1, admit="loose")


def _result(**kw: object) -> TuneResult:
    base = dict(
        controller="pi",
        gains={"kp": 4e-5, "ki": 1e-5},
        cost=1.0,
        experiment_costs={"E1": 1.0},
        case_costs={"E1@10N/mm": 0.5, "E1@100N/mm": 1.5},
        baseline_gains={"kp": 4e-5, "ki": 1e-5},
        baseline_cost=1.0,
        baseline_experiment_costs={"E1": 1.0},
        evaluations=10,
        budget=10,
        seed=0,
        interrupted=False,
        wall_time_s=1.0,
        experiments=("E1",),
        stiffnesses_n_per_mm=(10.0, 100.0),
        plant="planar",
        rulebase=None,
        baseline_case_costs={"E1@10N/mm": 0.5, "E1@100N/mm": 1.5},
        cheapest_gains={"kp": 1e-4, "ki": 3e-5},
        cheapest_cost=0.8,
        cheapest_case_costs={"E1@10N/mm": 0.6, "E1@100N/mm": 1.0},
    )
    base.update(kw)
    return TuneResult(**base)  # type: ignore[arg-type]


def test_kept_defaults_are_reported_with_the_reason() -> None:
    from fuzzkit.cli.tuning import tune_report_lines

    r = _result()
    assert r.kept_defaults
    assert r.refusals() == [("E1@10N/mm", 0.6, 0.5)]
    text = "\n".join(tune_report_lines(r, []))
    assert "kept the default gains: every cheaper candidate was worse" in text
    assert "was refused: worse than the default gains on E1@10N/mm (0.6 vs 0.5, +20.0 %)" in text
    assert "(the default gains)" in text
    # An admissible cheapest candidate is the result: nothing refused, nothing to explain.
    ok = _result(gains={"kp": 1e-4, "ki": 3e-5}, cost=0.8, cheapest_case_costs={})
    assert not ok.kept_defaults and ok.refusals() == []
    assert "kept the default gains" not in "\n".join(tune_report_lines(ok, []))
    # Nothing cheaper at all: said as such.
    none = _result(cheapest_cost=1.0, cheapest_case_costs={"E1@10N/mm": 0.5, "E1@100N/mm": 1.5})
    assert none.refusals() == []
    assert "none of the 10 gain sets tried was cheaper" in "\n".join(tune_report_lines(none, []))


def _case(label: str, default: float, tuned: float, d_trip: bool, t_trip: bool) -> object:
    from fuzzkit.studies.tuning_check import CaseComparison

    axes: dict[str, dict[str, object]] = {"z": {"settling_time_s": None, "overshoot_pct": 1.0}}
    return CaseComparison(label, "E1", 10.0, default, tuned, axes, axes, d_trip, t_trip)


def test_tune_warns_of_trips_and_of_a_result_no_better_than_its_start() -> None:
    """Issue 33 item 5: the share of the robust grid that trips is stated, and a result within
    1 % of its start (the README's old example: -0.0 %) or worse is said to be so."""
    from fuzzkit.cli.tuning import honesty_warnings, is_worse

    cases = [
        _case("E1@10N/mm", 0.5, 0.5, False, False),
        _case("E1@100N/mm", 1.5, 1.5, True, True),
        _case("E1@1000N/mm", 9.0, 9.0, True, True),
    ]
    kept = _result()  # the defaults kept: cost == baseline
    lines = honesty_warnings(kept, cases, "the default gains")
    assert lines == [
        "warning: the tuned gains trip the safety limit in 2 of 3 cases of the robust grid "
        "(67 %): E1@100N/mm, E1@1000N/mm; the default gains trip in 2",
        "warning: the result is not better than the default gains on the robust cost "
        "(1 vs 1, +0.0 %; less than 1 % cheaper)",
    ]
    assert not is_worse(kept)
    # 0.5 % cheaper is still "not better"; 2 % cheaper, without trips, warns of nothing
    assert "not better" in honesty_warnings(_result(cost=0.995), cases[:1], "x")[0]
    assert honesty_warnings(_result(cost=0.98), cases[:1], "x") == []
    worse = _result(cost=1.2)
    assert is_worse(worse)
    assert honesty_warnings(worse, [], "the gains of s.yaml") == [
        "warning: the result is worse than the gains of s.yaml on the robust cost "
        "(1.2 vs 1, +20.0 %)"
    ]


def test_tune_does_not_write_a_worse_result_without_force(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A result dearer than its start is reported and not written (exit 1); --force writes."""
    from fuzzkit.cli import main
    from fuzzkit.studies import tuning, tuning_check

    monkeypatch.setattr(
        tuning, "tune", lambda *a, **k: _result(gains={"kp": 9e-5, "ki": 2e-5}, cost=1.2)
    )
    monkeypatch.setattr(tuning_check, "compare_cases", lambda *a, **k: [])
    out = tmp_path / "gains.yaml"
    argv = ["tune", "E1", "--controller", "pi", "--quiet", "--out", str(out)]
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert "warning: the result is worse than the default gains on the robust cost" in err
    assert f"{out} not written" in err and "--force" in err
    assert not out.exists()
    assert main([*argv, "--force"]) == 0
    assert read_gains_file(out)["pi"].gains["kp"] == 9e-5


@pytest.mark.slow
def test_readme_tour_tuned_gains_no_worse_at_any_stiffness() -> None:
    """The tour the README showed before (tune E1 over 10, 100, 1000 N/mm), small budget: at every
    stiffness, the saved gains cost no more than the defaults when run again from scratch."""
    ks = (10.0, 100.0, 1000.0)
    result = tune(["E1"], "fuzzy-pi", stiffnesses_n_per_mm=ks, budget=12, seed=0, workers=2)
    from fuzzkit.loop.python_loop import load_surface

    surface = load_surface("macvicar_whelan")
    h = TUNING_HORIZON_S["E1"]
    for k in ks:
        exp = with_stiffness(experiment("E1"), k * 1e3)
        costs = [
            run_cost(run(exp, "planar", "fuzzy-pi", gains=g, surface=surface, duration_s=h))
            for g in (result.gains, result.baseline_gains)
        ]
        assert costs[0] <= costs[1] * (1 + 1e-3) + 1e-9, (k, costs)


def test_tuning_runs_keep_each_experiments_latency_unless_told() -> None:
    """Without ``latencies`` a case runs at its experiment's own latency, as ``simulate`` does:
    pricing it equals pricing at that latency given explicitly, and differs from (0, 0)."""
    from fuzzkit.studies.experiments import DEFAULT_GAINS

    gains = dict(DEFAULT_GAINS["pi"])
    own = TuningProblem.build(["E2"], "pi", plant="arm6", stiffnesses_n_per_mm=None, horizon_s=2.0)
    assert own.latency_of(0) is None
    lat = experiment("E2").latency_periods
    assert lat != (0, 0)

    def price(problem: TuningProblem) -> tuple[float, ...]:
        return evaluate_gains(problem, gains)

    explicit = TuningProblem.build(
        ["E2"], "pi", plant="arm6", stiffnesses_n_per_mm=None, horizon_s=2.0, latencies=[lat]
    )
    zero = TuningProblem.build(
        ["E2"], "pi", plant="arm6", stiffnesses_n_per_mm=None, horizon_s=2.0, latencies=[(0, 0)]
    )
    assert price(own) == price(explicit)
    assert price(own) != price(zero)


def test_tune_compares_tuned_with_defaults_per_stiffness_and_latency() -> None:
    """Tuned over one stiffness x two latencies on the compiled arm6 loop: the full-run check
    has one case per latency, each run at its own latency (the same run as ``simulate`` with
    ``--latency`` gives), and the printed table names the latency of each case."""
    from fuzzkit.cli.tuning import tune_report_lines
    from fuzzkit.loop.spec import RunSpec
    from fuzzkit.studies.batch import execute, gains_items
    from fuzzkit.studies.tuning_check import compare_cases

    lats = [(0, 0), (3, 3)]
    result = tune(
        ["E1"],
        "pi",
        plant="arm6",
        stiffnesses_n_per_mm=(20.0,),
        latencies=lats,
        budget=10,
        seed=0,
        workers=1,
    )
    assert result.latencies == tuple(lats)
    assert result.to_entry().provenance["latency_periods"] == [[0, 0], [3, 3]]
    cases = compare_cases(result)
    assert [c.latency for c in cases] == lats
    assert [c.label for c in cases] == ["E1@20N/mm@lat0:0", "E1@20N/mm@lat3:3"]
    for c in cases:
        row = execute(
            RunSpec(
                "E1",
                "pi",
                "arm6",
                stiffness_n_per_mm=20.0,
                latency=c.latency,
                gains=gains_items(result.baseline_gains),
            )
        )
        assert (row["sensor_delay"], row["command_delay"]) == c.latency
        assert c.default_axes["z"]["overshoot_pct"] == row["z_overshoot_pct"]
        assert c.default_axes["z"]["settling_time_s"] == row["z_settling_time_s"]
    # the delay changes the transient: the two cases are not one run printed twice
    assert cases[0].default_axes["z"] != cases[1].default_axes["z"]
    text = "\n".join(tune_report_lines(result, cases))
    assert "every case (experiment x stiffness x latency)" in text
    assert "E1@20N/mm@lat3:3 (" in text and "E1@20N/mm@lat0:0 (" in text


@pytest.mark.slow
def test_tuning_e3_on_arm6_prices_the_papers_3d_e3() -> None:
    """E3 on arm6 is the paper's geometry in ``tune`` as in ``simulate``: the compiled price
    of a case equals the Python loop's run on the 3-D world (floor and side wall), and
    differs from the shared E3 (sliding into the wall)."""
    from fuzzkit.studies.e3_arm6 import e3_arm6_experiment, make_e3_arm6_plant
    from fuzzkit.studies.experiments import DEFAULT_GAINS
    from fuzzkit.studies.tuning import TUNING_HORIZON_S, CaseRunner, TuningProblem

    pi = DEFAULT_GAINS["pi"]
    problem = TuningProblem.build(["E3"], "pi", plant="arm6", stiffnesses_n_per_mm=(10.0,))
    assert problem.paper_e3_cases == (True,)
    assert problem.cases[0].scenario.path == e3_arm6_experiment().scenario.path
    runner = CaseRunner(problem)
    assert runner.run_case(0, pi, 0.02).loop == "compiled"
    cost = runner.case_costs(pi)[0]
    h = min(TUNING_HORIZON_S["E3"], problem.cases[0].scenario.duration_s)
    exp3d = with_stiffness(e3_arm6_experiment(), 10e3)
    reference = run(exp3d, make_e3_arm6_plant(), "pi", gains=pi, duration_s=h)
    assert cost == pytest.approx(run_cost(reference), rel=1e-6)
    shared = run(with_stiffness(experiment("E3"), 10e3), "arm6", "pi", duration_s=h)
    assert abs(run_cost(shared) - cost) > 1e-3 * cost


def test_the_report_labels_tuned_gains_that_lose_to_the_defaults_per_case() -> None:
    from fuzzkit.report.tuned import case_verdict, tuned_vs_default_markdown

    dearer = _case("E1@5N/mm", 0.5, 0.6, False, False)
    trips = _case("E2@20N/mm", 0.5, 0.4, False, True)  # cheaper, but trips where default holds
    cheaper = _case("E3@5N/mm", 0.5, 0.4, True, True)
    same = _case("E3@10N/mm", 0.5, 0.5, False, False)
    assert [case_verdict(c) for c in (dearer, trips, cheaper, same)] == [  # type: ignore[arg-type]
        "**loses to the defaults**",
        "**loses to the defaults**",
        "better",
        "same",
    ]
    table = tuned_vs_default_markdown({"pi": [dearer, cheaper]})  # type: ignore[list-item]
    assert "| pi | E1@5N/mm | 0.5 -> 0.6 | +20.0 % | **loses to the defaults** |" in table
    # the committed report: every dearer case is labelled, and only those
    report = (Path(__file__).resolve().parent.parent / "docs/report/report.md").read_text()
    rows = [r for r in report.splitlines() if re.match(r"\| (pi|fuzzy-pi) \| E\d@", r)]
    assert len(rows) == 54
    for row in rows:
        dearer_row = re.search(r"\| \+[0-9.]+ % \|", row) is not None
        assert ("loses to the defaults" in row) == (dearer_row or "| no -> yes |" in row), row
