"""Digests of a few short MuJoCo runs, recorded from the code before issue 37 item 4's last
steps, so that every later change to the MuJoCo loop is checked bit for bit (not a test module).

Each run's recorded series (:data:`SERIES`, then the arm's and the contacts' points) is hashed
with SHA-256 over its dtype, shape and bytes (C order). ``tests/data/mujoco_digests.json`` holds
the digests with the versions of MuJoCo, numpy and numba that made them; MuJoCo's trajectories
are its own, so another MuJoCo release is another trajectory
(``tests/test_mujoco_digests.py`` says so instead of comparing).

Made with ``.venv/bin/python tests/_mujoco_digests.py`` (rewrites the file; about 5 s): only
when a change of trajectory is intended and explained.
"""

from __future__ import annotations

import hashlib
import json
import sys
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numba
import numpy as np

from fuzzkit.loop.compiled.generated_controller import (
    load_generated_controller,
    run_controller_spec,
)
from fuzzkit.loop.compiled_loop import run_compiled
from fuzzkit.loop.faults import fault
from fuzzkit.loop.generated import GeneratedLoopController
from fuzzkit.loop.python_loop import run
from fuzzkit.loop.result import RunResult
from fuzzkit.loop.timing import run_faults_and_latency
from fuzzkit.plants.mujoco_arm import ElasticMujocoArmPlant, MujocoArmPlant
from fuzzkit.studies.experiments import experiment

FILE = Path(__file__).parent / "data" / "mujoco_digests.json"

SERIES = (
    "t", "force", "force_sensor", "force_true", "setpoint", "e", "de", "du", "u",
    "tool_position", "nominal_position", "target_position", "joint_angles", "in_contact",
    "force_normal", "moving", "status", "rotation",
)  # fmt: skip


@dataclass(frozen=True)
class DigestRun:
    """One short run: its plant and loop, experiment, controller, fault, seed, length."""

    plant: str  # "mujoco" or "mujoco-elastic"
    loop: str  # "compiled" (callback, generated C) or "python-ramp" (no callback)
    name: str
    controller: str
    fault_kind: str
    seed: int
    duration_s: float
    latency: tuple[int, int] | None = None

    @property
    def key(self) -> str:
        lat = "" if self.latency is None else f"-lat{self.latency[0]}.{self.latency[1]}"
        return (
            f"{self.plant}-{self.loop}-{self.name}-{self.controller}-{self.fault_kind}"
            f"-s{self.seed}-{self.duration_s:g}s{lat}"
        )


#: every run reaches contact (E1 at 1.86 s, E2 at 1.0 s, E3's wall at 4.2 s)
RUNS = (
    DigestRun("mujoco", "compiled", "E1", "fuzzy-pi", "spike", 1, 2.6),
    DigestRun("mujoco-elastic", "compiled", "E1", "pi", "none", 2, 2.6),
    DigestRun("mujoco", "compiled", "E2", "pi", "delay", 3, 1.5, (0, 3)),
    DigestRun("mujoco-elastic", "compiled", "E3", "fuzzy-pi", "nan", 4, 4.6, (2, 1)),
    DigestRun("mujoco", "python-ramp", "E1", "pi", "dropout", 5, 2.4),
)


def _plant(run_: DigestRun) -> MujocoArmPlant:
    return ElasticMujocoArmPlant() if run_.plant == "mujoco-elastic" else MujocoArmPlant()


def execute(run_: DigestRun) -> RunResult:
    """The run, the generated C controller in either loop (the Python ramp: no callback)."""
    exp = experiment(run_.name)
    generated = load_generated_controller(run_controller_spec(exp, run_.controller, None))
    faults = fault(run_.fault_kind, run_.seed)
    if run_.loop == "compiled":
        return run_compiled(
            exp, run_.plant, seed=run_.seed, faults=faults, duration_s=run_.duration_s,
            latency=run_.latency, generated_controller=generated,
        )  # fmt: skip
    _, sensor_delay, _ = run_faults_and_latency(exp, run_.seed, faults, run_.latency)
    hybrid = GeneratedLoopController(generated.spec, sensor_delay, impl="c")
    return run(
        exp, _plant(run_), run_.controller, hybrid=hybrid, seed=run_.seed, faults=faults,
        duration_s=run_.duration_s, latency=run_.latency,
    )  # fmt: skip


def _sha(values: object) -> str:
    a = np.ascontiguousarray(np.asarray(values))
    h = hashlib.sha256(f"{a.dtype.str}{a.shape}".encode())
    h.update(a.tobytes())
    return h.hexdigest()


def digests(r: RunResult) -> dict[str, str]:
    """Each recorded series' SHA-256 (:func:`_sha`), the points' per list."""
    out = {key: _sha(getattr(r, key)) for key in SERIES}
    out["arm_points"] = _sha(np.concatenate([np.ravel(p) for p in r.arm_points]))
    out["contact_points"] = _sha(
        np.concatenate([np.ravel(p) for p in r.contact_points] or [np.zeros(0)])
    )
    return out


def versions() -> dict[str, str]:
    return {"mujoco": mujoco.__version__, "numpy": np.__version__, "numba": numba.__version__}


def main() -> int:
    from fuzzkit.plants.mujoco_servo import ServoCallback

    try:
        table = {run_.key: digests(execute(run_)) for run_ in RUNS}
    finally:
        ServoCallback.uninstall()
    FILE.write_text(
        json.dumps({"versions": versions(), "runs": table}, indent=1, sort_keys=True) + "\n",
        encoding="utf-8",
    )
    print(f"wrote {FILE} ({len(table)} runs)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
