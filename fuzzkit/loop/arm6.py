"""The arm6 plant's adapter: the 6-DOF kinematic IRB 140 and its compiled loop.

The plant is reset in Python (:meth:`~fuzzkit.plants.arm6.Arm6Plant.reset`: the start pose's
IK with its seeds), read into arrays (:func:`fuzzkit.plants.arm6_period.pack`), then one
compiled call (:func:`fuzzkit.loop.compiled.arm6_run.run_arm6`) runs every period.
"""

from __future__ import annotations

import numpy as np

from fuzzkit.loop.adapter import PlantAdapter
from fuzzkit.loop.compiled import arm6_run as K
from fuzzkit.loop.compiled import period as P
from fuzzkit.loop.compiled.common import (
    ControllerArgs,
    fields_record,
    recording,
    result_from_recording,
    run_kernel,
)
from fuzzkit.loop.result import RunResult
from fuzzkit.loop.task import Experiment
from fuzzkit.plants.arm6 import Arm6Plant
from fuzzkit.plants.arm6_period import IK_STATUS_NAMES, pack
from fuzzkit.plants.contact import sensor_noise
from fuzzkit.plants.contract import ContactPlant

_IK_MESSAGES = {
    "max_iterations": "IK not converged this period",
    "unreachable": "target unreachable: going to the closest pose",
    "limit": "target needs motion past a joint limit",
}


def run_arm6_compiled(
    exp: Experiment, plant: ContactPlant, ctrl: ControllerArgs, seed: int
) -> RunResult:
    """One compiled run on ``plant`` (an :class:`~fuzzkit.plants.arm6.Arm6Plant`; the
    adapter's ``compiled``)."""
    if not isinstance(plant, Arm6Plant):
        raise TypeError(f"the arm6 compiled loop runs an Arm6Plant (got {type(plant).__name__})")
    scn = exp.scenario
    n = ctrl.periods
    reset = plant.reset(scn, seed=seed)
    arrays = pack(plant)  # UnsupportedPlant (a ConfigError) for what the kernel lacks
    noise = sensor_noise(scn.sensor.noise_std_n, seed, n + 1)
    dof = arrays.q.shape[0]
    own = {"ik": np.empty(n, dtype=np.int64), "limited": np.empty(n, dtype=np.bool_)}
    rec = recording(n, dof, dof + 2, arrays.obj_kind.shape[0], **own)
    scalars = np.zeros(P.N_RESULTS)
    reset_force = np.asarray(reset.force, dtype=np.float64).copy()
    plant_arrays = fields_record(arrays)
    _, cpu, wall = run_kernel(K.run_arm6, plant_arrays, noise, reset_force, ctrl, rec, scalars)
    messages: dict[str, int] = {}
    for code, count in zip(*np.unique(rec["ik"], return_counts=True), strict=True):
        name = IK_STATUS_NAMES[int(code)]
        if name in _IK_MESSAGES:
            messages[_IK_MESSAGES[name]] = int(count)
    limited = int(np.count_nonzero(rec["limited"]))
    if limited:
        messages["joint speed limit"] = limited
    return result_from_recording(exp, "arm6", ctrl, seed, rec, scalars, messages, cpu, wall)


#: Building the plant (parsing the robot description) costs two thirds of a short run, and
#: ``reset`` rebuilds its whole state: the compiled loop keeps one per process.
ADAPTER = PlantAdapter("arm6", Arm6Plant, compiled=run_arm6_compiled, reuse=True)
