"""Where a controller period's time goes on the MuJoCo IRB 140 (issue 37 item 4), per part.

Run: ``.venv/bin/python bench/bench_mujoco_period.py`` (about 15 s on a 2-core machine).

Rows, CPU microseconds per 4 ms period of E1 (best of 3; the machine is shared):

* the whole period, in the compiled loop (``run_spec`` of E1 on ``mujoco``: one numba call for
  the run, the generated C controller) and in the Python loop (``--loop python``);
* its parts, each timed alone in a numba loop of its own, as the compiled period calls it:
  the physics (``fuzzkit_mj_steps``: four ``mj_step`` with the servo ramp as the C control
  callback, from the pressing state E1 reaches), the tool's contact forces
  (``fuzzkit_tool_contacts``), the inner loop's reference (the path pose and the compiled IK,
  warm-started along E1's path, as the run does); the physics also from free space (E1 at
  1 s), which costs less, so the physics row is an upper bound of its share;
* the rest (the controller, sensor model, faults, latency queues, recording): the whole
  compiled period less those parts.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from typing import Any

import numba
import numpy as np

from fuzzkit.loop.compiled.mujoco_run import M_IK_ITER, M_TOL_O, M_TOL_P, MOST_CONTACTS
from fuzzkit.plants.arm6_period import ik, matrix_from_quat, pose_at

#: periods timed per part
N = 3000


@numba.njit
def _physics(mj_steps: Any, m: np.uint64, d: np.uint64, u: Any, n_sub: int, n: int) -> int:
    bad = 0
    for _ in range(n):
        u[1] = 0.0  # the callback's substep count, as the compiled period resets it
        bad += mj_steps(m, d, n_sub)
    return bad


@numba.njit
def _contacts(tool_contacts: Any, m: np.uint64, d: np.uint64, tip: int, n: int) -> int:
    total, normals, points = np.empty(3), np.empty(3 * MOST_CONTACTS), np.empty(3 * MOST_CONTACTS)
    count = 0
    for _ in range(n):
        count += tool_contacts(
            m, d, tip, total.ctypes, normals.ctypes, points.ctypes, MOST_CONTACTS
        )
    return count


@numba.njit
def _reference(plant: tuple[Any, ...], dt: float, n: int) -> int:
    a_links, a_tool_r, a_tool_p, a_lower, a_upper = plant[0], plant[1], plant[2], plant[3], plant[4]
    a_path_t, a_path_pos, a_path_quat = plant[6], plant[7], plant[8]
    params, q_ik, ik_work = plant[20], plant[23], plant[26]
    nominal, quat, rt = np.empty(3), np.empty(4), np.empty((3, 3))
    q_try = np.empty(q_ik.shape[0])
    worst = 0
    for k in range(n):
        pose_at(a_path_t, a_path_pos, a_path_quat, (k + 1) * dt, nominal, quat)
        matrix_from_quat(quat, rt)
        q_try[:] = q_ik
        status = ik(rt, nominal, q_try, a_links, a_tool_r, a_tool_p, a_lower, a_upper,
                    params[M_TOL_P], params[M_TOL_O], int(params[M_IK_ITER]), ik_work)  # fmt: skip
        q_ik[:] = q_try
        worst = max(worst, status)
    return worst


def _cpu_us(work: Callable[[], object], n: int, repeat: int = 3) -> float:
    """Least CPU microseconds per period of ``work`` (``n`` periods) over ``repeat`` runs."""
    work()  # compile / warm
    best = float("inf")
    for _ in range(repeat):
        c0 = time.process_time()
        work()
        best = min(best, time.process_time() - c0)
    return 1e6 * best / n


def _period_us(loop: str) -> float:
    from fuzzkit.loop.spec import RunSpec
    from fuzzkit.studies.batch import run_spec

    spec = RunSpec("E1", "fuzzy-pi", plant="mujoco", loop=loop)
    run_spec(spec)
    runs = [run_spec(spec) for _ in range(3)]
    return min(1e6 * r.cpu_time_s / len(r.t) for r in runs)


def main() -> int:
    """Measure and print the table; returns the process exit code."""
    from fuzzkit.loop.compiled_loop import run_compiled
    from fuzzkit.loop.mujoco import mujoco_plant, pack
    from fuzzkit.plants.mujoco_arm import MujocoArmPlant
    from fuzzkit.studies.experiments import experiment

    compiled, python = _period_us("compiled"), _period_us("python")
    plant = mujoco_plant()
    assert isinstance(plant, MujocoArmPlant) and plant.servo is not None, plant
    exp = experiment("E1")
    servo = plant.servo

    def physics_from(duration_s: float, pressing: bool) -> float:
        """The physics' cost from E1's state at ``duration_s``."""
        r = run_compiled(exp, plant, "fuzzy-pi", duration_s=duration_s)
        assert r.in_contact[-1] == pressing, duration_s
        m, d = np.uint64(plant.model._address), np.uint64(plant.data._address)
        u = plant.data.userdata
        return _cpu_us(lambda: _physics(servo.steps, m, d, u, 4, N), N)

    free = physics_from(1.0, False)
    physics = physics_from(4.0, True)
    m, d = np.uint64(plant.model._address), np.uint64(plant.data._address)
    contacts = _cpu_us(lambda: _contacts(servo.contacts, m, d, plant._tip, N), N)
    plant.reset(exp.scenario, seed=0)
    arrays = pack(plant)
    reference = _cpu_us(lambda: _reference(arrays.plant, 0.004, N), N)
    rest = compiled - physics - contacts - reference
    rows = [
        ("period, Python loop (--loop python)", python, ""),
        ("period, compiled loop", compiled, f"{0.004e6 / compiled:,.0f}x real time"),
        ("  physics: 4 x mj_step + servo callback", physics, "pressing"),
        ("  (the same in free space)", free, "not in the sum"),
        ("  tool contact forces (C)", contacts, ""),
        ("  reference: path pose + IK (numba)", reference, ""),
        ("  rest: controller, sensor, faults, recording", rest, "period less the parts: at least"),
    ]
    print(f"{'E1 on mujoco, fuzzy-PI':<48} {'us CPU':>8} {'share':>6}")
    print("-" * 80)
    for label, us, note in rows:
        share = (
            f"{100 * us / compiled:5.0f}%"
            if label.startswith("  ") and not label.startswith("  (")
            else ""
        )
        print(f"{label:<48} {us:8.1f} {share:>6}  {note}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
