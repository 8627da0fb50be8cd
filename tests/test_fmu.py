"""``fuzzkit compile SPEC --target fmu`` (issue 22 item 1): an FMI 2.0 Co-Simulation FMU of the
whole controller, checked by a third party (FMPy validates it and simulates it) against
``fuzzkit replay`` on hostile sensor logs."""

from __future__ import annotations

import zipfile
from pathlib import Path

import fmpy
import numpy as np
import numpy.typing as npt
import pytest
from _codegen_util import needs_cc
from _replay_logs import read_out, write_log
from fmpy.validation import validate_fmu

from fuzzkit.cli import main
from fuzzkit.control.spec_reader import load_spec
from fuzzkit.studies.sensor_logs import hostile_log

REPO = Path(__file__).parent.parent
#: fuzzy-PI with the tool's weight compensated (inputs fx fy fz r11..r33)
SPEC_GRAVITY = REPO / "docs" / "examples" / "controller.yaml"
#: fuzzy-PI, tare and low-pass, no gravity compensation (inputs fx fy fz only)
SPEC_PLAIN = REPO / "docs" / "examples" / "controller_tilt_tare_only.yaml"
#: incremental PI with gravity compensation
SPEC_PI = REPO / "docs" / "examples" / "controller_pi.yaml"
#: fuzzy-PI on the interval type-2 rule base (its surface the IT2 engine's table), front end
SPEC_IT2 = REPO / "docs" / "examples" / "controller_it2.yaml"

pytestmark = needs_cc


def _compile(spec: Path, out: Path) -> Path:
    assert main(["compile", str(spec), "--target", "fmu", "--out", str(out)]) == 0
    return out


def _reference_replay(
    spec: Path, log: Path, out: Path, capsys: pytest.CaptureFixture[str]
) -> npt.NDArray[np.float64]:
    """``fuzzkit replay SPEC --impl reference`` of ``log``: t, ux, uy, uz, status per row."""
    argv = ["replay", str(spec), "--forces", str(log), "--out", str(out), "--impl", "reference"]
    assert main(argv) == 0
    capsys.readouterr()
    return read_out(out)[1]


def _simulate(
    fmu: Path, forces: npt.NDArray[np.float64], rotations: npt.NDArray[np.float64] | None, dt: float
) -> npt.NDArray[np.void]:
    """FMPy drives the FMU with the log as discrete inputs, one communication step per period."""
    n = forces.shape[0]
    names = ["fx", "fy", "fz"] + (
        [f"r{i}{j}" for i in range(1, 4) for j in range(1, 4)] if rotations is not None else []
    )
    signals = np.zeros(n, dtype=[("time", np.float64)] + [(c, np.float64) for c in names])
    signals["time"] = np.arange(n) * dt
    for k, c in enumerate(names[:3]):
        signals[c] = forces[:, k]
    if rotations is not None:
        for k, c in enumerate(names[3:]):
            signals[c] = rotations[:, k]
    result: npt.NDArray[np.void] = fmpy.simulate_fmu(
        str(fmu),
        stop_time=n * dt,
        step_size=dt,
        output_interval=dt,
        input=signals,
        output=["ux", "uy", "uz", "status"],
    )
    return result


@pytest.mark.parametrize(
    ("spec_path", "gravity"),
    [(SPEC_GRAVITY, True), (SPEC_PLAIN, False), (SPEC_PI, True), (SPEC_IT2, True)],
)
def test_fmu_validates_and_equals_replay_on_a_hostile_log(
    spec_path: Path, gravity: bool, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    spec = load_spec(spec_path)
    fmu = _compile(spec_path, tmp_path / f"{spec.name}.fmu")
    assert validate_fmu(str(fmu)) == []
    md = fmpy.read_model_description(str(fmu))
    assert md.coSimulation is not None and md.modelExchange is None
    assert float(md.defaultExperiment.stepSize) == spec.period_s
    inputs = [v.name for v in md.modelVariables if v.causality == "input"]
    rot = [f"r{i}{j}" for i in range(1, 4) for j in range(1, 4)]
    assert inputs == ["fx", "fy", "fz", *(rot if gravity else []), "tare", "reset"]
    outputs = {v.name: v.type for v in md.modelVariables if v.causality == "output"}
    assert outputs == {"ux": "Real", "uy": "Real", "uz": "Real", "status": "Integer"}

    forces, rotations = hostile_log(spec)
    assert np.isnan(forces).any() and np.isinf(forces).any()
    assert np.nanmax(np.abs(forces[np.isfinite(forces)])) > spec.safety.limit_n
    log = tmp_path / "log.csv"
    write_log(log, forces, rotations)
    ref = _reference_replay(spec_path, log, tmp_path / "ref.csv", capsys)

    got = _simulate(fmu, forces, rotations if gravity else None, spec.period_s)
    n = forces.shape[0]
    # row 0 is the state before the first step; row k + 1 follows the k-th period
    assert got.shape[0] == n + 1
    assert [got[c][0] for c in ("ux", "uy", "uz", "status")] == [0, 0, 0, 0]
    u = np.column_stack([got["ux"], got["uy"], got["uz"]])[1:]
    assert np.abs(u - ref[:, 1:4]).max() <= 1e-9
    np.testing.assert_array_equal(got["status"][1:], ref[:, 4].astype(np.int64))
    # the log exercises the controller: engaged, holds, rejects spikes, trips, and moves
    status = got["status"][1:]
    assert all((status & bit).any() for bit in (1, 2, 4, 64))
    assert np.abs(u).max() > 1e-4


def test_fmu_is_reproducible_and_carries_its_sources(tmp_path: Path) -> None:
    a = _compile(SPEC_GRAVITY, tmp_path / "a.fmu").read_bytes()
    b = _compile(SPEC_GRAVITY, tmp_path / "b.fmu").read_bytes()
    assert a == b
    with zipfile.ZipFile(tmp_path / "a.fmu") as zf:
        names = zf.namelist()
        assert names == sorted(names)
        assert {i.date_time for i in zf.infolist()} == {(1980, 1, 1, 0, 0, 0)}
        assert "binaries/linux64/e1_fuzzy.so" in names
        for f in (
            "modelDescription.xml",
            "sources/e1_fuzzy_controller.c",
            "sources/e1_fuzzy_surface.c",
            "sources/e1_fuzzy_controller_fmi2.c",
            "sources/fmi2Functions.h",
        ):
            assert f in names
    # the sources rebuild the FMU elsewhere: FMPy's own CMake build of sources/ (without our
    # binary) runs the same as the shipped binary
    from fmpy.build import build_platform_binary

    rebuilt = tmp_path / "rebuilt"
    with zipfile.ZipFile(tmp_path / "a.fmu") as zf:
        zf.extractall(rebuilt)
    (rebuilt / "binaries" / "linux64" / "e1_fuzzy.so").unlink()
    (tmp_path / "cmake").mkdir()
    build_platform_binary(rebuilt, build_dir=tmp_path / "cmake")
    assert (rebuilt / "binaries" / "linux64" / "e1_fuzzy.so").is_file()
    spec = load_spec(SPEC_GRAVITY)
    forces, rotations = hostile_log(spec, n=150)
    want = _simulate(tmp_path / "a.fmu", forces, rotations, spec.period_s)
    got = _simulate(rebuilt, forces, rotations, spec.period_s)
    np.testing.assert_array_equal(got["status"], want["status"])
    assert np.abs(got["uz"] - want["uz"]).max() <= 1e-12


def test_a_step_that_is_not_whole_periods_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    spec = load_spec(SPEC_PLAIN)
    fmu = _compile(SPEC_PLAIN, tmp_path / "p.fmu")
    forces = np.zeros((10, 3))
    with pytest.raises(Exception, match="fmi2DoStep"):
        _simulate(fmu, forces, None, 1.5 * spec.period_s)
    # two periods per communication step: two controller steps on the held input, i.e. replay
    # of the log with every sample repeated, read every second period
    held = hostile_log(spec)[0][:150]
    log = tmp_path / "held.csv"
    write_log(log, np.repeat(held, 2, axis=0), None)
    ref = _reference_replay(SPEC_PLAIN, log, tmp_path / "ref.csv", capsys)
    got = _simulate(fmu, held, None, 2.0 * spec.period_s)
    assert got.shape[0] == held.shape[0] + 1
    u = np.column_stack([got["ux"], got["uy"], got["uz"]])[1:]
    assert np.abs(u - ref[1::2, 1:4]).max() <= 1e-9
    np.testing.assert_array_equal(got["status"][1:], ref[1::2, 4].astype(np.int64))
    assert np.abs(u).max() > 1e-4  # the controller moved: one step per period would differ


def test_fmu_refuses_rule_bases_and_folders(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(["compile", "macvicar_whelan", "--target", "fmu", "--out", str(tmp_path / "x")])
    err = capsys.readouterr().err
    assert code == 2 and "controller spec" in err
    assert main(["compile", str(SPEC_PLAIN), "--target", "fmu", "--out", str(tmp_path)]) == 2
    assert "is a directory" in capsys.readouterr().err
    assert main(["compile", str(SPEC_PLAIN), "--target", "fmu", "--type", "float",
                 "--out", str(tmp_path / "f.fmu")]) == 2  # fmt: skip
    assert not (tmp_path / "f.fmu").exists() and not (tmp_path / "x").exists()
