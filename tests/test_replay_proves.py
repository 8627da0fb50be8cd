"""Replay proves the run (issue 40 item 8): it compares the status bits, and its tolerance is
relative to the corrections' size, so a controller whose gain is 1e-10 of its value off, in
the generated code or in the reference, does not reproduce the run."""

from __future__ import annotations

from pathlib import Path

import pytest
from _codegen_util import needs_cc
from _replay_logs import SPEC, replayed_difference, reproduces, run_cli

from fuzzkit.studies.batch import RunSpec, run_spec
from fuzzkit.studies.run_table import run_csv

pytestmark = needs_cc

#: the example spec's gains as its file spells them, and the same 1e-10 of their value off
GAINS = "gains: {kp: 0.2, ki: 0.05, kx: 0.0002}"
OFF = {
    "kx": "gains: {kp: 0.2, ki: 0.05, kx: 0.00020000000002}",
    "ki": "gains: {kp: 0.2, ki: 0.050000000005, kx: 0.0002}",
}


@pytest.fixture(scope="module")
def run_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A generated-C run of the example spec on arm6 with spikes and latency, as CSV."""
    result = run_spec(
        RunSpec("E1", plant="arm6", controller_spec=str(SPEC), fault="spike", latency=(1, 1),
                seed=2, duration_s=2.0)
    )  # fmt: skip
    assert result.loop == "compiled" and result.status is not None
    csv = tmp_path_factory.mktemp("run") / "run.csv"
    csv.write_text(run_csv(result), encoding="utf-8")
    return csv


def _copy(run_file: Path, tmp_path: Path) -> Path:
    csv = tmp_path / "run.csv"
    csv.write_text(run_file.read_text(encoding="utf-8"), encoding="utf-8")
    return csv


@pytest.mark.parametrize("impl", ["reference", "c"])
def test_the_runs_own_spec_reproduces_it(
    run_file: Path, impl: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert reproduces(capsys, SPEC, _copy(run_file, tmp_path), impl)


@pytest.mark.parametrize("gain", sorted(OFF))
@pytest.mark.parametrize("impl", ["reference", "c"])
def test_a_gain_1e_10_off_does_not_reproduce_the_run(
    run_file: Path, gain: str, impl: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # the reference (impl reference) or the generated C (impl c) of a spec whose gain differs
    # by 1e-10 of its value from the run's
    text = SPEC.read_text(encoding="utf-8")
    assert text.count(GAINS) == 2
    off = tmp_path / "controller.yaml"
    off.write_text(text.replace(GAINS, OFF[gain]), encoding="utf-8")
    csv = _copy(run_file, tmp_path)
    assert replayed_difference(capsys, off, csv, impl) > 0.0
    assert not reproduces(capsys, off, csv, impl)


def test_a_status_bit_the_run_did_not_return_does_not_reproduce_it(
    run_file: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    lines = run_file.read_text(encoding="utf-8").splitlines()
    col = lines[0].split(",").index("status_bits")
    row = lines[400].split(",")
    row[col] = str(int(row[col]) ^ 16)  # SATURATED flipped on one period, corrections kept
    lines[400] = ",".join(row)
    csv = tmp_path / "run.csv"
    csv.write_text("\n".join(lines) + "\n", encoding="utf-8")
    code, printed, _ = run_cli(capsys, "replay", str(SPEC), "--forces", str(csv), "--impl", "c",
                               "--out", str(tmp_path / "u.csv"))  # fmt: skip
    assert code == 1
    assert "status bits: 1 row differs from the run's, the first at period 399" in printed
    assert "corrections (u<a>_m): 0 m" in printed and "DOES NOT reproduce the run" in printed
