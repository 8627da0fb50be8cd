"""Run an experiment through the compiled loop and return the runner's :class:`RunResult`.

:func:`run_compiled` takes the arguments of :func:`fuzzkit.studies.runner.run` that the compiled
loop models; :func:`compiled_supports` says when it applies (the ``arm6`` and ``planar``
plants). Its controller is the run's controller spec generated as C (double) and called by
address every period. The
plant is reset in Python (arm6: the start pose's IK with its seeds; planar: the pymunk space),
then one compiled call runs every period (the planar one in
:mod:`fuzzkit.studies.compiled.planar_loop`).
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np

from fuzzkit.errors import ConfigError
from fuzzkit.plants.arm6 import Arm6Plant
from fuzzkit.plants.arm6_period import IK_STATUS_NAMES, pack
from fuzzkit.plants.contact import sensor_noise
from fuzzkit.studies.compiled import arm6_run as K
from fuzzkit.studies.compiled import period as P
from fuzzkit.studies.compiled.common import (
    ControllerArgs,
    controller_args,
    result_from_recording,
    warm_up,
)
from fuzzkit.studies.compiled.generated_controller import (
    GeneratedController,
    load_generated_controller,
    run_controller_spec,
)
from fuzzkit.studies.compiled.table import TableArrays, cached_table, load_table
from fuzzkit.studies.experiments import Experiment
from fuzzkit.studies.faults import Faults
from fuzzkit.studies.runner import RunResult

if TYPE_CHECKING:
    from fuzzkit.planar_sim import PlanarArmPlant


#: Plants the compiled loop runs.
COMPILED_PLANTS = ("arm6", "planar", "mujoco", "mujoco-elastic")

_IK_MESSAGES = {
    "max_iterations": "IK not converged this period",
    "unreachable": "target unreachable: going to the closest pose",
    "limit": "target needs motion past a joint limit",
}


def compiled_supports(plant: str) -> bool:
    """True when the compiled loop models ``plant``."""
    return plant in COMPILED_PLANTS


@lru_cache(maxsize=1)
def _shared_plant() -> Arm6Plant:
    """One default arm6 plant per process: ``reset`` rebuilds its whole state for every run,
    and building it (parsing the robot description) cost two thirds of a short run."""
    return Arm6Plant()


def compiled_table(rulebase: str = "macvicar_whelan", tolerance: float = 1e-3) -> TableArrays:
    """:func:`load_table`'s arrays, from the on-disk cache after the first build."""
    from fuzzkit.control.loop_rulebase import load_loop_rulebase

    return cached_table(
        load_loop_rulebase(rulebase), tolerance, lambda: load_table(rulebase, tolerance)
    )


def run_compiled(
    exp: Experiment,
    plant: str | Arm6Plant | PlanarArmPlant = "arm6",
    controller: str = "pi",
    *,
    gains: Mapping[str, float] | None = None,
    rulebase: str = "macvicar_whelan",
    seed: int = 0,
    faults: Faults | None = None,
    duration_s: float | None = None,
    latency: tuple[int, int] | None = None,
    generated_controller: GeneratedController | None = None,
) -> RunResult:
    """Run ``exp`` on the arm6 or the planar plant with the compiled loop; same semantics as
    ``runner.run``.

    The controller is always generated C: ``generated_controller``
    (:func:`~fuzzkit.studies.compiled.generated_controller.load_generated_controller`), else
    the run's controller spec (:func:`~fuzzkit.studies.compiled.generated_controller.
    run_controller_spec` of ``exp``, ``controller``, ``gains``, ``rulebase``) generated,
    compiled (cached) and loaded. ``faults`` and ``latency`` default to the experiment's, as in
    ``runner.run``.

    Raises
    ------
    ConfigError
        For a plant the compiled loop does not model or an unknown controller.
        :class:`~fuzzkit.plants.contract.UnsupportedPlant` (a ConfigError) for a plant with
        objects or modes the kernel lacks (the Python loop runs it).
    ToolchainError
        No C compiler to build the controller.
    SimulationError
        When the planar arm's state becomes non-finite, as the Python plant raises it.
    """
    if isinstance(plant, str):
        if not compiled_supports(plant):
            raise ConfigError(
                f"the compiled loop runs on {', '.join(COMPILED_PLANTS)} (got {plant!r}); "
                "use --loop python"
            )
        plant = _mujoco_plant(plant) if plant.startswith("mujoco") else (
            _shared_plant() if plant == "arm6" else _planar_plant()
        )  # fmt: skip
    if generated_controller is None:
        generated_controller = load_generated_controller(
            run_controller_spec(exp, controller, gains, rulebase)
        )
    ctrl = controller_args(exp, generated_controller, seed, faults, duration_s, latency)
    controller = generated_controller.spec.kind
    from fuzzkit.plants.mujoco_arm import MujocoArmPlant

    if isinstance(plant, MujocoArmPlant):  # an Arm6Plant too: first
        from fuzzkit.studies.compiled.mujoco_loop import run_mujoco_compiled

        return run_mujoco_compiled(exp, plant, controller, ctrl, seed)
    if isinstance(plant, Arm6Plant):
        return _run_arm6(exp, plant, controller, ctrl, seed)
    from fuzzkit.studies.compiled.planar_loop import run_planar_compiled

    return run_planar_compiled(exp, plant, controller, ctrl, seed)


def _mujoco_plant(name: str) -> Arm6Plant:
    """``--plant mujoco`` or ``mujoco-elastic`` as the registry builds it (servo callback
    compiled; a MujocoArmPlant, which is an Arm6Plant)."""
    from fuzzkit.plants.mujoco_arm import MujocoArmPlant
    from fuzzkit.studies.plants import make_plant

    plant = make_plant(name)
    if not isinstance(plant, MujocoArmPlant):
        raise ConfigError(f"plant {name!r} is not a MuJoCo plant")
    return plant


def _planar_plant() -> PlanarArmPlant:
    from fuzzkit.planar_sim import PlanarArmPlant

    return PlanarArmPlant()


def _run_arm6(
    exp: Experiment, plant: Arm6Plant, controller: str, ctrl: ControllerArgs, seed: int
) -> RunResult:
    scn = exp.scenario
    n = ctrl.periods
    reset = plant.reset(scn, seed=seed)
    arrays = pack(plant)  # UnsupportedPlant (a ConfigError) for what the kernel lacks
    noise = sensor_noise(scn.sensor.noise_std_n, seed, n + 1)
    dof = arrays.q.shape[0]
    n_obj = max(arrays.obj_kind.shape[0], 1)
    rec = {
        "t": np.empty(n),
        "force": np.empty((n, 3)),
        "force_sensor": np.empty((n, 3)),
        "force_true": np.empty((n, 3)),
        "e": np.empty((n, 3)),
        "de": np.empty((n, 3)),
        "du": np.empty((n, 3)),
        "u": np.empty((n, 3)),
        "tool": np.empty((n, 3)),
        "nominal": np.empty((n, 3)),
        "target": np.empty((n, 3)),
        "joints": np.empty((n, dof)),
        "contact": np.empty(n, dtype=np.bool_),
        "force_normal": np.empty((n, 3)),
        "moving": np.empty(n, dtype=np.bool_),
        "ik": np.empty(n, dtype=np.int64),
        "limited": np.empty(n, dtype=np.bool_),
        "arm": np.empty((n, dof + 2, 3)),
        "points": np.zeros((n, n_obj, 3)),
        "npoints": np.empty(n, dtype=np.int64),
        "status": np.empty(n, dtype=np.int64),
    }
    scalars = np.zeros(P.N_RESULTS)
    reset_force = np.asarray(reset.force, dtype=np.float64).copy()
    a = arrays
    args = (
        a.links, a.tool_r, a.tool_p, a.lower, a.upper, a.dq_max, a.path_t, a.path_pos,
        a.path_quat, a.obj_kind, a.obj_p, a.obj_terms, a.obj_nterms, a.obj_grid, a.rot_task,
        a.offset,
        a.params, a.q, a.q_ref, a.q_ik, a.stick, a.state, noise, reset_force,
        ctrl.cp, ctrl.selection, ctrl.setpoints, ctrl.c_step, ctrl.c_state, ctrl.spike, ctrl.nan,
    )  # fmt: skip
    warm_up(K.run_arm6, args, rec, scalars, ctrl)
    wall0 = time.perf_counter()
    cpu0 = time.process_time()
    K.run_arm6(
        *args,
        rec["t"], rec["force"], rec["force_sensor"], rec["force_true"], rec["e"], rec["de"],
        rec["du"], rec["u"], rec["tool"], rec["nominal"], rec["target"], rec["joints"],
        rec["contact"], rec["force_normal"], rec["moving"], rec["ik"], rec["limited"], rec["arm"],
        rec["points"], rec["npoints"], rec["status"],
        scalars,
    )  # fmt: skip
    cpu = time.process_time() - cpu0
    wall = time.perf_counter() - wall0
    messages: dict[str, int] = {}
    for code, count in zip(*np.unique(rec["ik"], return_counts=True), strict=True):
        name = IK_STATUS_NAMES[int(code)]
        if name in _IK_MESSAGES:
            messages[_IK_MESSAGES[name]] = int(count)
    limited = int(np.count_nonzero(rec["limited"]))
    if limited:
        messages["joint speed limit"] = limited
    return result_from_recording(
        exp, "arm6", controller, ctrl, seed, rec, scalars, messages, cpu, wall
    )
