"""The MuJoCo plants' adapters: the IRB 140 in MuJoCo (``mujoco``) and with joint springs
(``mujoco-elastic``), built with the servo ramp compiled as MuJoCo's control callback
(:mod:`fuzzkit.plants.mujoco_servo`) where a C compiler exists, the Python ramp otherwise (the
plant says so in its first period's messages). No compiled loop yet: the Python loop runs
them, with the run's generated controller.

The plant layer compiles nothing (it imports no code generation); this module compiles the
plant's C source with the kit's toolchain (:func:`fuzzkit.codegen.toolchain.cached_library`,
the on-disk cache of the compiled controllers) against the headers of the MuJoCo that is
loaded, once per process. MuJoCo is imported only when a plant is built.
"""

from __future__ import annotations

import functools
from pathlib import Path
from typing import TYPE_CHECKING

from fuzzkit.codegen.toolchain import cached_library
from fuzzkit.errors import ToolchainError
from fuzzkit.loop.adapter import PlantAdapter
from fuzzkit.plants.contract import ContactPlant

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
    try:
        library = cached_library({"mujoco_servo.c": text}, "mujoco_servo", flags=flags)
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


ADAPTER = PlantAdapter("mujoco", mujoco_plant)
ELASTIC = PlantAdapter("mujoco-elastic", elastic_mujoco_plant)
