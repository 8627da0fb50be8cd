"""The FMU's tunable parameters and its ``tare`` and ``reset`` inputs (issue 33 item 7): FMPy
changes gains, a set point and the safety limit mid-simulation and pulses tare and reset, and
the result equals ``fuzzkit replay --schedule`` with the same changes at the same periods."""

from __future__ import annotations

import math
from pathlib import Path

import fmpy
import numpy as np
import numpy.typing as npt
import pytest
from _codegen_util import needs_cc
from _replay_logs import read_out, write_log
from fmpy.fmi2 import FMU2Slave
from fmpy.validation import validate_fmu

from fuzzkit.cli import main
from fuzzkit.control.spec_reader import load_spec
from fuzzkit.studies.sensor_logs import hostile_log

REPO = Path(__file__).parent.parent
SPEC_FUZZY = REPO / "docs" / "examples" / "controller.yaml"
SPEC_PI = REPO / "docs" / "examples" / "controller_pi.yaml"
ROT = [f"r{i}{j}" for i in range(1, 4) for j in range(1, 4)]

pytestmark = needs_cc


def _compile(spec: Path, out: Path) -> Path:
    assert main(["compile", str(spec), "--target", "fmu", "--out", str(out)]) == 0
    return out


class Cosim:
    """The FMU driven period by period through FMPy's FMI 2.0 API."""

    def __init__(self, fmu: Path, tmp: Path) -> None:
        self.md = fmpy.read_model_description(str(fmu))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.slave = FMU2Slave(
            guid=self.md.guid,
            unzipDirectory=fmpy.extract(str(fmu), str(tmp / "unzipped")),
            modelIdentifier=self.md.coSimulation.modelIdentifier,
            instanceName="tunable",
        )
        self.slave.instantiate()
        self.slave.setupExperiment(startTime=0.0)
        self.slave.enterInitializationMode()
        self.slave.exitInitializationMode()

    def run(
        self,
        forces: npt.NDArray[np.float64],
        rotations: npt.NDArray[np.float64],
        period: float,
        changes: dict[int, list[tuple[str, float]]],
    ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]]:
        n = forces.shape[0]
        u = np.empty((n, 3))
        status = np.empty(n, dtype=np.int64)
        names = ["fx", "fy", "fz", *ROT]
        refs = [self.vr[c] for c in names]
        pulsed: list[str] = []
        for k in range(n):
            for event in pulsed:  # an event is a pulse: true for one step
                self.slave.setBoolean([self.vr[event]], [False])
            pulsed = []
            for name, value in changes.get(k, []):
                if name in ("tare", "reset"):
                    self.slave.setBoolean([self.vr[name]], [True])
                    pulsed.append(name)
                else:
                    self.slave.setReal([self.vr[name]], [value])
            self.slave.setReal(refs, [*forces[k], *rotations[k]])
            self.slave.doStep(currentCommunicationPoint=k * period, communicationStepSize=period)
            u[k] = self.slave.getReal([self.vr["ux"], self.vr["uy"], self.vr["uz"]])
            status[k] = self.slave.getInteger([self.vr["status"]])[0]
        return u, status

    def close(self) -> None:
        self.slave.terminate()
        self.slave.freeInstance()


def _changes(fuzzy: bool, spec_kp: float, spec_ki: float) -> dict[int, list[tuple[str, float]]]:
    """Changes at periods of the hostile log's segments (120 samples each): gains in the spike
    trains, set points in the NaN bursts, reset in the set-point steps, tare in the tilted
    tool, and the limit lowered before the force rises past it (it trips only then)."""
    first = [("kp_z", 2.5 * spec_kp), ("ki_z", 0.5 * spec_ki)]
    if fuzzy:
        first.append(("kx_z", 0.0003))
    return {
        150: first,
        300: [("setpoint_z", 14.0), ("setpoint_x", 1.5)],
        500: [("reset", 1.0)],
        620: [("tare", 1.0), ("kp_x", 2.0 * spec_kp)],
        700: [("limit_n", 16.0)],
    }


@pytest.mark.parametrize("spec_path", [SPEC_FUZZY, SPEC_PI])
def test_gains_changed_mid_simulation_equal_replay_with_the_same_schedule(
    spec_path: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    spec = load_spec(spec_path)
    fmu = _compile(spec_path, tmp_path / f"{spec.name}.fmu")
    assert validate_fmu(str(fmu)) == []
    forces, rotations = hostile_log(spec, n=120, seed=11)  # 840 samples: spikes, NaN, trips
    z = next(a for a in spec.axes if a.axis == "z")
    changes = _changes(spec.kind == "fuzzy-pi", z.kp, z.ki)
    log = tmp_path / "log.csv"
    write_log(log, forces, rotations)
    schedule = tmp_path / "schedule.csv"
    rows = [f"{k},{name},{value!r}" for k, cs in changes.items() for name, value in cs]
    schedule.write_text("period,name,value\n" + "\n".join(rows) + "\n")
    outs = {}
    for name, extra in (("tuned", ["--schedule", str(schedule)]), ("fixed", [])):
        out = tmp_path / f"{name}.csv"
        argv = ["replay", str(spec_path), "--forces", str(log), "--out", str(out), "--impl",
                "reference", *extra]  # fmt: skip
        assert main(argv) == 0, capsys.readouterr().err
        outs[name] = read_out(out)[1]
    capsys.readouterr()
    sim = Cosim(fmu, tmp_path)
    try:
        u, status = sim.run(forces, rotations, spec.period_s, changes)
    finally:
        sim.close()
    ref = outs["tuned"]
    assert float(np.max(np.abs(u - ref[:, 1:4]))) <= 1e-9
    np.testing.assert_array_equal(status, ref[:, 4].astype(np.int64))
    # the changes mattered: the same replay without them parts from it at the first change
    fixed = outs["fixed"]
    np.testing.assert_array_equal(fixed[:150, 1:5], ref[:150, 1:5])
    assert float(np.max(np.abs(fixed[150:300, 3] - ref[150:300, 3]))) > 1e-6
    # reset at 500 cleared the trip latch and restarted the tare; tare at 620 started another;
    # the limit lowered at 700 trips on the rising force, which the spec's limit does not
    bits = ref[:, 4].astype(np.int64)
    tripped, taring = 1 << 2, 1 << 5
    assert bits[499] & tripped and not bits[500] & tripped
    assert bits[500] & taring and bits[620] & taring and not fixed[620, 4].astype(int) & taring
    assert not (bits[500:700] & tripped).any() and (bits[700:] & tripped).any()


def test_the_model_description_declares_tunable_parameters_and_the_inputs(
    tmp_path: Path,
) -> None:
    spec = load_spec(SPEC_FUZZY)
    fmu = _compile(SPEC_FUZZY, tmp_path / "f.fmu")
    md = fmpy.read_model_description(str(fmu))
    params = {
        v.name: (v.variability, v.initial, float(v.start))
        for v in md.modelVariables
        if v.causality == "parameter"
    }
    want = {}
    for a in spec.axes:
        for g in ("kp", "ki", "kx"):
            want[f"{g}_{a.axis}"] = ("tunable", "exact", getattr(a, g))
        want[f"setpoint_{a.axis}"] = ("tunable", "exact", a.setpoint_n)
    want["limit_n"] = ("tunable", "exact", spec.safety.limit_n)
    assert params == want
    booleans = {v.name: v.causality for v in md.modelVariables if v.type == "Boolean"}
    assert booleans == {"tare": "input", "reset": "input"}


@pytest.mark.parametrize(
    "name, value", [("kp_z", -0.1), ("kx_z", 0.0), ("ki_z", math.nan), ("limit_n", 0.0),
                    ("setpoint_z", math.inf), ("setpoint_z", 25.0), ("setpoint_x", -30.0),
                    ("limit_n", 10.0), ("limit_n", 0.9)],
)  # fmt: skip
def test_a_value_the_reference_refuses_is_refused_and_kept(
    tmp_path: Path, name: str, value: float
) -> None:
    fmu = _compile(SPEC_FUZZY, tmp_path / "f.fmu")
    sim = Cosim(fmu, tmp_path)
    try:
        before = sim.slave.getReal([sim.vr[name]])[0]
        with pytest.raises(Exception, match="fmi2SetReal"):
            sim.slave.setReal([sim.vr[name]], [value])
        assert sim.slave.getReal([sim.vr[name]])[0] == before
    finally:
        sim.close()


@pytest.mark.parametrize(
    "text, where, message",
    [
        ("t,name,value\n", ":1:1", "expected the header period,name,value"),
        ("period,name,value\n5,kp_q,1\n", ":2:3", "unknown parameter 'kp_q' (did you mean"),
        ("period,name,value\n5,kx_z,1\n", ":2:3", "unknown parameter 'kx_z'"),  # PI: no kx
        ("period,name,value\n-1,kp_z,1\n", ":2:1", "period must be a sample of the log"),
        ("period,name,value\n99,kp_z,1\n", ":2:1", "0 to 9, got '99'"),
        ("period,name,value\n1,kp_z,abc\n", ":2:8", "expected a number, got 'abc'"),
        ("period,name,value\n1,kp_z,-1\n", ":2:8", "kp_z must be >= 0 (a PI gain)"),
        ("period,name,value\n1,limit_n,0\n", ":2:11", "limit_n must be > 0"),
        ("period,name,value\n1,tare,2\n", ":2:8", "tare is an event: its value is 1"),
        ("period,name,value\n1,kp_z,nan\n", ":2:8", "must be a finite number"),
        ("period,name,value\n1,kp_z\n", ":2:1", "expected 3 cells, got 2"),
        ("period,name,value\n1,setpoint_z,25\n", ":2", "now 25 N against 25 N"),
        ("period,name,value\n1,setpoint_z,20\n3,limit_n,18\n", ":3", "now 20 N against 18 N"),
        ("period,name,value\n1,limit_n,0.5\n", ":2", "now 10 N against 0.5 N"),
    ],
)
def test_bad_schedules_are_located_errors(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str, where: str, message: str
) -> None:
    log = tmp_path / "log.csv"
    log.write_text("fx,fy,fz," + ",".join(ROT) + "\n" + "0,0,1,1,0,0,0,1,0,0,0,1\n" * 10)
    schedule = tmp_path / "s.csv"
    schedule.write_text(text)
    out = tmp_path / "u.csv"
    code = main(["replay", str(SPEC_PI), "--forces", str(log), "--out", str(out),
                 "--impl", "reference", "--schedule", str(schedule)])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2 and f"{schedule}{where}: " in err and message in err, err
    assert not out.exists()


def test_a_schedule_needs_the_reference(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    log = tmp_path / "log.csv"
    log.write_text("fx,fy,fz," + ",".join(ROT) + "\n" + "0,0,1,1,0,0,0,1,0,0,0,1\n" * 10)
    schedule = tmp_path / "s.csv"
    schedule.write_text("period,name,value\n2,kp_z,1e-4\n")
    for extra in (["--impl", "c"], ["--impl", "python"], [], ["--compare"]):
        code = main(["replay", str(SPEC_PI), "--forces", str(log), "--out",
                     str(tmp_path / "u.csv"), "--schedule", str(schedule), *extra])  # fmt: skip
        assert code == 2 and "--schedule" in capsys.readouterr().err
