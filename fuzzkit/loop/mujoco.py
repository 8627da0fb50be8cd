"""The MuJoCo plants' adapters: the IRB 140 in MuJoCo (``mujoco``) and with joint springs
(``mujoco-elastic``), built with the servo ramp compiled as MuJoCo's control callback
(:mod:`fuzzkit.plants.mujoco_servo`) where a C compiler exists, the Python ramp otherwise (the
plant says so in its first period's messages), and their compiled loop: the plant reset in
Python, read into arrays (:func:`pack`), then one compiled call
(:func:`fuzzkit.loop.compiled.mujoco_run.run_mujoco`) runs every period, MuJoCo's C library
called by address. What the kernel does not model raises
:class:`~fuzzkit.plants.contract.UnsupportedPlant` (the Python loop runs it): a plant without
its servo callback (no C compiler), the reference IK (``compiled_ik=False``), ``strict`` mode,
a drifting sensor bias or a tilting tool. A tool's weight needs nothing: MuJoCo's wrist sensor
measures it.

The plant layer compiles nothing (it imports no code generation); this module compiles the
plant's C source with the kit's toolchain (:func:`fuzzkit.codegen.toolchain.cached_library`,
the on-disk cache of the compiled controllers) against the headers of the MuJoCo that is
loaded, once per process. MuJoCo is imported only when a plant is built.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from fuzzkit.codegen.toolchain import cached_library
from fuzzkit.errors import SimulationError, ToolchainError
from fuzzkit.loop.adapter import PlantAdapter
from fuzzkit.loop.compiled import period as P
from fuzzkit.loop.compiled.common import (
    ControllerArgs,
    recording,
    result_from_recording,
    run_kernel,
)
from fuzzkit.loop.result import RunResult
from fuzzkit.loop.task import Experiment
from fuzzkit.plants.arm6_period import IK_STATUS_NAMES, ik_workspace
from fuzzkit.plants.contact import padded_terms, sensor_noise
from fuzzkit.plants.contract import ContactPlant, UnsupportedPlant, wrist_sensor_extras

if TYPE_CHECKING:
    from fuzzkit.plants.mujoco_arm import MujocoArmPlant
    from fuzzkit.plants.mujoco_servo import ServoCallback

#: the callback is host code against MuJoCo's headers, not embedded code: C11, else as strict
HOST_FLAGS = ("-std=c11", "-Wall", "-Wextra", "-Werror", "-pedantic")


def mujoco_include_dir() -> Path:
    """The MuJoCo headers shipped in the ``mujoco`` wheel (``mujoco/include``)."""
    import mujoco

    return Path(mujoco.__file__).resolve().parent / "include"


@functools.cache
def servo_callback() -> ServoCallback | str:
    """The compiled servo ramp, or why there is none (no compiler, no headers, a build that
    failed): the reason the plant then states."""
    import mujoco

    from fuzzkit.plants.mujoco_servo import ServoCallback, source_text

    include = mujoco_include_dir()
    if not (include / "mujoco" / "mujoco.h").is_file():
        return f"servo ramp in Python: no MuJoCo headers at {include}"
    # the headers' version is part of the source, so the cache never mixes mjData layouts;
    # C11, which MuJoCo's headers need (anonymous unions); no contraction into fused
    # multiply-adds: the ramp's doubles are the Python ramp's
    text = f"/* MuJoCo {mujoco.mj_versionString()} */\n" + source_text()
    flags = (*HOST_FLAGS, "-O2", "-ffp-contract=off", f"-I{include}")
    shipped = sorted(include.parent.glob("libmujoco.so*"))
    if not shipped:
        return f"servo ramp in Python: no libmujoco.so beside {include}"
    # linked against the very library the bindings loaded (dlopen finds it mapped already)
    lib_dir = shipped[0].parent
    libs = ("-lm", f"-L{lib_dir}", f"-l:{shipped[0].name}", f"-Wl,-rpath,{lib_dir}")
    try:
        library = cached_library({"mujoco_servo.c": text}, "mujoco_servo", flags=flags, libs=libs)
        return ServoCallback(library)
    except (ToolchainError, RuntimeError, OSError) as exc:
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        return f"servo ramp in Python, not as a C control callback: {first}"


def _with_callback(plant: MujocoArmPlant) -> MujocoArmPlant:
    servo = servo_callback()
    if isinstance(servo, str):
        plant.use_servo_callback(None, servo)
    else:
        plant.use_servo_callback(servo)
    return plant


def mujoco_plant() -> ContactPlant:
    """``--plant mujoco``: the rigid IRB 140 in MuJoCo, servo ramp in C where it compiles."""
    from fuzzkit.plants.mujoco_arm import MujocoArmPlant

    return _with_callback(MujocoArmPlant())


def elastic_mujoco_plant() -> ContactPlant:
    """``--plant mujoco-elastic``: the same with joint springs on axes 1-3."""
    from fuzzkit.plants.mujoco_arm import ElasticMujocoArmPlant

    return _with_callback(ElasticMujocoArmPlant())


#: the messages of a period whose IK did not converge (as the compiled arm6 loop words them)
IK_MESSAGES = {
    "max_iterations": "IK not converged this period",
    "unreachable": "target unreachable: going to the closest pose",
    "limit": "target needs motion past a joint limit",
}


@dataclass(slots=True)
class MujocoArrays:
    """Everything :func:`~fuzzkit.loop.compiled.mujoco_run.run_mujoco` reads of the plant,
    in its argument order: the arm (as arm6's compiled twin reads it), the MuJoCo indices, the
    rough profiles, parameters and state, and the ``MjData`` views it writes and reads."""

    plant: tuple[Any, ...]
    mujoco: tuple[Any, ...]
    tip: int


def pack(plant: MujocoArmPlant) -> MujocoArrays:
    """Read a freshly reset ``plant`` into the kernel's arrays (the compiled loop's).

    Raises
    ------
    UnsupportedPlant
        For what the kernel does not model (module docstring).
    """
    from fuzzkit.loop.compiled import mujoco_run as K
    from fuzzkit.plants.environment import _roughness_terms
    from fuzzkit.plants.mujoco_model import PROFILE_HALF_THICKNESS_M

    servo = plant.servo
    if servo is None:
        raise UnsupportedPlant(
            "the compiled mujoco loop needs the servo callback ("
            + (plant.servo_note or "not given")
            + ")"
        )
    scn = plant.scenario
    # a tool's weight is no extra here: MuJoCo's wrist sensor measures it
    lacks = [x for x in wrist_sensor_extras(scn) if not x.startswith("a tool weight")]
    if plant.params.strict:
        lacks.append("strict mode")
    if lacks:
        raise UnsupportedPlant(f"the compiled mujoco loop does not model {', '.join(lacks)}")
    m, d = plant.model, plant.data
    profiles = plant._profiles
    prof_p = np.zeros((len(profiles), 5))
    term_lists = []
    for k, (_, s) in enumerate(profiles):
        prof_p[k] = (s.x_min, s.x_max, s.height_m, s.offset_m, s.tilt_rad)
        term_lists.append(
            _roughness_terms(
                s.seed, s.roughness_rms_m, s.wavelength_min_m, s.wavelength_max_m, s.n_waves
            )
        )
    prof_terms, prof_nterms = padded_terms(term_lists)
    p, sensor = plant.params, scn.sensor
    params = np.zeros(K.N_M_PARAMS)
    params[K.M_DT] = plant._dt
    params[K.M_TOL_P] = p.ik_position_tolerance
    params[K.M_TOL_O] = p.ik_orientation_tolerance
    params[K.M_IK_ITER] = p.ik_iterations
    params[K.M_CUTOFF] = sensor.cutoff_hz
    params[K.M_RATE] = sensor.rate_hz
    params[K.M_BIAS : K.M_BIAS + 3] = sensor.bias_n
    params[K.M_HALF_THICKNESS] = PROFILE_HALF_THICKNESS_M
    fs = plant._sensor
    state = np.zeros(K.N_M_STATE)
    state[K.MS_T] = plant._t
    state[K.MS_NEXT_SAMPLE] = fs._next_t
    state[K.MS_FRESH] = 1.0 if fs._fresh else 0.0
    state[K.MS_FILTERED : K.MS_FILTERED + 3] = fs._filtered
    state[K.MS_LATEST : K.MS_LATEST + 3] = fs._latest
    layout = np.zeros(K.N_LAYOUT, dtype=np.int64)
    layout[K.L_MODEL], layout[K.L_DATA] = m._address, d._address
    layout[K.L_TIP], layout[K.L_NSUB] = plant._tip, plant._n_sub
    poses = plant.path.poses
    if plant._ik_arrays is None:
        raise UnsupportedPlant("the compiled mujoco loop runs the compiled IK only")
    arm = (
        *plant._ik_arrays,  # links, tool rotation and offset, joint limits: the plant's own IK's
        np.array(plant._dq_max, dtype=np.float64),
        np.array([q.t_s for q in poses], dtype=np.float64),
        np.array([q.position for q in poses], dtype=np.float64),
        np.array([q.orientation for q in poses], dtype=np.float64),
        np.array(scn.rotation, dtype=np.float64),
        np.array(plant._offset, dtype=np.float64),
        np.array(plant._kv_over_kp, dtype=np.float64),
        np.array(plant._servo_qpos, dtype=np.int64),
        np.array(plant._link_qpos, dtype=np.int64),
        np.array(plant._elastic, dtype=np.bool_),
        np.array(plant._arm_bodies, dtype=np.int64),
        prof_p,
        prof_terms,
        prof_nterms,
        np.array([mocap for mocap, _ in profiles], dtype=np.int64),
        params,
        layout,
        np.array(plant._q_ref, dtype=np.float64),
        np.array(plant._q_ik, dtype=np.float64),
        np.array(plant._ref_prev, dtype=np.float64),
        state,
        ik_workspace(len(plant._q_ik)),  # the IK's scratch, so that a period allocates nothing
    )
    views = (
        d.userdata, d.qpos, d.sensordata, d.geom_xpos, d.xpos,
        d.mocap_pos, d.mocap_quat, servo.steps, servo.contacts,
    )  # fmt: skip
    return MujocoArrays(plant=arm, mujoco=views, tip=plant._tip)


def run_mujoco_compiled(
    exp: Experiment, plant: ContactPlant, ctrl: ControllerArgs, seed: int
) -> RunResult:
    """``exp`` on the MuJoCo ``plant`` in the compiled loop with the controller ``ctrl`` (the
    adapters' ``compiled``).

    Raises
    ------
    UnsupportedPlant
        For what the kernel does not model (the Python loop runs it).
    SimulationError
        When the simulation diverges, as the Python plant raises it.
    """
    from fuzzkit.loop.compiled import mujoco_run as K
    from fuzzkit.plants.mujoco_arm import MujocoArmPlant

    if not isinstance(plant, MujocoArmPlant):
        raise TypeError(
            f"the mujoco compiled loop runs a MujocoArmPlant (got {type(plant).__name__})"
        )
    scn = exp.scenario
    n = ctrl.periods
    reset = plant.reset(scn, seed=seed)
    arrays = pack(plant)
    noise = sensor_noise(scn.sensor.noise_std_n, seed, n + 1)
    dof = len(plant._q_ref)
    n_bodies = len(plant._arm_bodies)
    rec = recording(
        n, dof, n_bodies + 1, K.MOST_CONTACTS,
        ik=np.empty(n, dtype=np.int64),
        limited=np.empty(n, dtype=np.int64),  # bit masks of the joints and of the servos
        saturated=np.empty(n, dtype=np.int64),
    )  # fmt: skip
    scalars = np.zeros(P.N_RESULTS)
    reset_force = np.asarray(reset.force, dtype=np.float64).copy()
    views, mj_steps, tool_contacts = arrays.mujoco[:-2], *arrays.mujoco[-2:]
    done, cpu, wall = run_kernel(
        K.run_mujoco, arrays.plant, noise, reset_force, ctrl, rec, scalars,
        extra=(views, mj_steps, tool_contacts),
    )  # fmt: skip
    done = int(done)
    if done < n:
        raise SimulationError(
            f"t={rec['t'][done]:.3f} s: the MuJoCo simulation diverged (a contact or joint "
            "stiffness too high for its 1 kHz physics step)"
        )
    return result_from_recording(
        exp, plant.name, ctrl, seed, rec, scalars, _messages(plant, rec), cpu, wall
    )


def _messages(plant: MujocoArmPlant, rec: dict[str, Any]) -> dict[str, int]:
    """The plant's messages, counted per period, as the Python plant words them."""
    names = [j.name for j in plant._robot_base.joints]
    out: dict[str, int] = {}

    def count(text: str, times: int) -> None:
        if times:
            out[text] = out.get(text, 0) + int(times)

    for code, times in zip(*np.unique(rec["ik"], return_counts=True), strict=True):
        count(IK_MESSAGES.get(IK_STATUS_NAMES[int(code)], ""), times)
    out.pop("", None)
    for key, what in (("limited", "joint speed limit on"), ("saturated", "servo torque limit on")):
        for mask, times in zip(*np.unique(rec[key], return_counts=True), strict=True):
            if mask:
                on = ", ".join(n for i, n in enumerate(names) if int(mask) >> i & 1)
                count(f"{what} {on}", times)
    return out


#: Building the plant (the robot description, the servo gains' model) costs 60 ms, twenty
#: times its ``reset``, which rebuilds the whole state: the compiled loop keeps one per process.
ADAPTER = PlantAdapter("mujoco", mujoco_plant, compiled=run_mujoco_compiled, reuse=True)
ELASTIC = PlantAdapter(
    "mujoco-elastic", elastic_mujoco_plant, compiled=run_mujoco_compiled, reuse=True
)
