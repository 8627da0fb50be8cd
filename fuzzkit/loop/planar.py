"""The planar plant's adapter: the pymunk two-link arm and its compiled loop.

The plant is reset in Python (:meth:`PlanarArmPlant.reset` builds the pymunk space), read into
arrays (:func:`fuzzkit.planar_sim.arm_period.pack`), then one compiled call
(:func:`fuzzkit.loop.compiled.planar_run.run_planar`) runs every period, calling Chipmunk
directly on that space.
"""

from __future__ import annotations

import numpy as np

from fuzzkit.errors import SimulationError
from fuzzkit.loop.adapter import PlantAdapter
from fuzzkit.loop.compiled import period as P
from fuzzkit.loop.compiled.common import (
    ControllerArgs,
    fields_record,
    recording,
    result_from_recording,
    run_kernel,
)
from fuzzkit.loop.compiled.planar_run import run_planar
from fuzzkit.loop.result import RunResult
from fuzzkit.loop.task import Experiment
from fuzzkit.planar_sim import PlanarArmPlant
from fuzzkit.planar_sim.arm_period import STEP_NON_FINITE, pack, sensor_samples
from fuzzkit.plants.contact import sensor_noise
from fuzzkit.plants.contract import ContactPlant

#: What ``PlanarArmPlant.step`` says, per flag of ``plant_step`` (index 1, 2, 3).
_MESSAGES = (
    "target out of reach: joint targets clamped to the workspace boundary",
    "joint 1 at its torque limit ({:g} N m)",
    "joint 2 at its torque limit ({:g} N m)",
)


def run_planar_compiled(
    exp: Experiment, plant: ContactPlant, ctrl: ControllerArgs, seed: int
) -> RunResult:
    """One compiled run on ``plant`` (a :class:`~fuzzkit.planar_sim.PlanarArmPlant`; the
    adapter's ``compiled``)."""
    if not isinstance(plant, PlanarArmPlant):
        raise TypeError(
            f"the planar compiled loop runs a PlanarArmPlant (got {type(plant).__name__})"
        )
    scn = exp.scenario
    n = ctrl.periods
    reset = plant.reset(scn, seed=seed)
    a = pack(plant)  # UnsupportedPlant (a ConfigError) for what the kernel lacks
    noise = sensor_noise(
        scn.sensor.noise_std_n, seed, sensor_samples(scn.period_s, scn.sensor.rate_hz, n)
    )
    rec = recording(n, 2, 4, a.obj_kind.shape[0], flags=np.zeros((n, 4), dtype=np.int64))
    scalars = np.zeros(P.N_RESULTS)
    reset_force = np.asarray(reset.force, dtype=np.float64).copy()
    done, cpu, wall = run_kernel(
        run_planar, fields_record(a), noise, reset_force, ctrl, rec, scalars
    )
    flags = rec["flags"]
    if done < n and flags[done, 0] == STEP_NON_FINITE:
        t = float(a.state[0])
        raise SimulationError(f"planar arm state became non-finite at t={t:.3f} s")
    messages: dict[str, int] = {}
    limits = (0.0, *plant.params.torque_limit_nm)
    for i in (1, 2, 3):
        count = int(np.count_nonzero(flags[:, i]))
        if count:
            messages[_MESSAGES[i - 1].format(limits[i - 1])] = count
    return result_from_recording(exp, "planar", ctrl, seed, rec, scalars, messages, cpu, wall)


ADAPTER = PlantAdapter("planar", PlanarArmPlant, compiled=run_planar_compiled)
