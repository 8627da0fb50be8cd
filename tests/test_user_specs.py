"""Users' own controllers, end to end (issue 28 items 2 and 3): the user-style rule bases of
``tests/data/user/`` and the shipped example specs go through validate, simulate on both plants
(with faults and latency), replay of the run's CSV, tune and compile.

Replay equality: ``fuzzkit replay SPEC --forces run.csv`` reads the ``simulate --csv`` file as
it is and must reproduce the run's corrections exactly with ``--impl c`` (the compiled loop ran
that code) and with ``--impl reference`` within 1e-12 of the corrections' largest magnitude (the
reference controller: the exact engine against the generated surface, rounding only), with the
same status bits in every row.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from _codegen_util import needs_cc
from _replay_logs import replayed_difference, reproduces

from fuzzkit.cli import main
from fuzzkit.loop.spec import RunSpec
from fuzzkit.studies.batch import run_spec
from fuzzkit.studies.run_table import run_csv

ROOT = Path(__file__).resolve().parent.parent
USER = ROOT / "tests" / "data" / "user"
USER_SPECS = {
    name: USER / f"spec_{name}.yaml" for name in ("nonuniform5", "renamed", "gauss_prod", "user_pi")
}
SHIPPED = {
    "example_fuzzy": ROOT / "docs" / "examples" / "controller.yaml",
    "example_pi": ROOT / "docs" / "examples" / "controller_pi.yaml",
}
#: plant -> (fault, (sensor, command) latency) of the replayed runs
RUNS = {"arm6": ("spike", (1, 1)), "planar": ("nan", (2, 0))}

pytestmark = needs_cc


@pytest.mark.parametrize("plant", sorted(RUNS))
@pytest.mark.parametrize("name", sorted({**USER_SPECS, **SHIPPED}))
def test_a_run_replays_to_its_corrections(
    name: str, plant: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    spec = {**USER_SPECS, **SHIPPED}[name]
    fault, latency = RUNS[plant]
    result = run_spec(
        RunSpec("E1", plant=plant, controller_spec=str(spec), fault=fault, latency=latency,
                seed=2, duration_s=3.5)
    )  # fmt: skip
    assert result.loop == "compiled" and "generated C controller" in result.controller_impl
    assert result.latency_periods == latency and result.faults > 0
    assert not result.tripped and result.engaged_time_s is not None
    assert float(np.max(np.abs(result.u))) > 1e-4  # the controller corrected
    csv = tmp_path / "run.csv"
    csv.write_text(run_csv(result), encoding="utf-8")
    assert replayed_difference(capsys, spec, csv, "c") == 0.0
    assert reproduces(capsys, spec, csv, "reference")


def test_replay_of_a_run_sees_a_different_controller(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # the comparison is not blind: another spec's controller on the same run's samples differs
    result = run_spec(
        RunSpec("E1", plant="arm6", controller_spec=str(USER_SPECS["renamed"]), duration_s=3.0)
    )
    csv = tmp_path / "run.csv"
    csv.write_text(run_csv(result), encoding="utf-8")
    assert replayed_difference(capsys, USER_SPECS["gauss_prod"], csv, "c") > 1e-6


@pytest.mark.parametrize("name", sorted(USER_SPECS))
def test_a_user_spec_validates_and_compiles(
    name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    spec = USER_SPECS[name]
    assert main(["validate", str(spec)]) == 0
    assert f"{spec}: ok (controller spec user_{name}: fuzzy-pi" in capsys.readouterr().out
    for target in ("c", "python"):
        out = tmp_path / target
        argv = ["compile", str(spec), "--target", target, "--out", str(out), "--verify"]
        assert main([*argv, "--type", "double"] if target == "c" else argv) == 0
        assert (out / f"user_{name}_controller.{'c' if target == 'c' else 'py'}").is_file()
    capsys.readouterr()


@pytest.mark.slow
@pytest.mark.parametrize("name", ["renamed", "nonuniform5"])
def test_a_user_spec_tunes(name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from fuzzkit.control.spec_reader import load_spec

    spec, gains, tuned = USER_SPECS[name], tmp_path / "gains.yaml", tmp_path / "tuned.yaml"
    argv = ["tune", "E1", "--spec", str(spec), "--plant", "planar", "--budget", "12"]
    argv += ["--workers", "1", "--quiet", "--out", str(gains), "--spec-out", str(tuned)]
    assert main(argv) == 0
    assert gains.is_file() and tuned.is_file()
    out, original = load_spec(tuned), load_spec(spec)
    # the same rule base (its path now relative to the written spec) and role mapping
    assert out.rulebase == original.rulebase and out.inputs == original.inputs
    # the spec written carries the gains file's tuned gains (which may be the spec's own, when
    # no candidate beat them within the budget)
    import yaml

    def found(node: object, key: str) -> list[float]:
        if isinstance(node, dict):
            return [float(v) for k, v in node.items() if k == key] + [
                x for v in node.values() for x in found(v, key)
            ]
        return [x for v in node for x in found(v, key)] if isinstance(node, list) else []

    doc = yaml.safe_load(gains.read_text(encoding="utf-8"))
    for key in ("kp", "ki", "kx"):
        assert found(doc, key) == [getattr(out.axes[0], key)], key
        assert all(getattr(a, key) == getattr(out.axes[0], key) for a in out.axes)
    capsys.readouterr()


@pytest.mark.slow
def test_a_spec_whose_axes_differ_tunes_from_its_own_gains(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Issue 41: ``spec_user_pi`` has x at kp 0.25, ki 0.04, kx 0.00015 and z at 0.2, 0.05,
    0.0002. tune starts from and is judged against those (not the defaults), searches z's
    gains (the set point) and writes x's scaled with them, each ratio kept."""
    from fuzzkit.control.gains import read_gains
    from fuzzkit.control.spec_reader import load_spec

    spec, gains, tuned = USER_SPECS["user_pi"], tmp_path / "gains.yaml", tmp_path / "tuned.yaml"
    argv = ["tune", "E1", "--spec", str(spec), "--plant", "planar", "--stiffness", "10"]
    argv += ["--budget", "10", "--workers", "1", "--quiet", "--out", str(gains)]
    assert main([*argv, "--spec-out", str(tuned)]) == 0
    printed = capsys.readouterr()
    assert printed.err.count("axes have different gains") == 1, printed.err
    assert "searches axis z's" in printed.err
    assert f"vs the gains of {spec} " in printed.out and "default gains" not in printed.out
    out, original = load_spec(tuned), load_spec(spec)
    x0, z0 = original.axes
    x1, z1 = out.axes
    entry = read_gains(gains, "fuzzy-pi")
    assert (entry["kp"], entry["ki"], entry["kx"]) == (z1.kp, z1.ki, z1.kx)
    for key in ("kp", "ki", "kx"):
        ratio = getattr(x0, key) / getattr(z0, key)
        assert getattr(x1, key) / getattr(z1, key) == pytest.approx(ratio, rel=1e-11), key
