"""The plants a study can run on, by name: ``planar`` (pymunk), ``arm6`` (6-DOF kinematic) and
``mujoco`` (6-DOF dynamic, MuJoCo)."""

from __future__ import annotations

import importlib
from collections.abc import Callable

from fuzzkit.errors import ConfigError
from fuzzkit.plants.contract import ContactPlant

#: Plant name -> ``"module:factory"``; the factory takes no arguments and returns a ContactPlant.
#: Imported lazily so that choosing one plant never imports another's dependencies.
PLANTS: dict[str, str] = {
    "planar": "fuzzkit.planar_sim:PlanarArmPlant",
    "arm6": "fuzzkit.plants.arm6:Arm6Plant",  # 6-DOF IRB 140 kinematic plant (issue 5)
    "mujoco": "fuzzkit.plants.mujoco_arm:MujocoArmPlant",  # the IRB 140 in MuJoCo (issue 30)
    "mujoco-elastic": "fuzzkit.plants.mujoco_arm:ElasticMujocoArmPlant",  # with joint springs
}


def make_plant(name: str) -> ContactPlant:
    """Build the plant registered as ``name`` (see :data:`PLANTS`)."""
    target = PLANTS.get(name)
    if target is None:
        raise ConfigError(f"unknown plant {name!r} (expected one of {', '.join(sorted(PLANTS))})")
    module_name, _, attr = target.partition(":")
    factory: Callable[[], ContactPlant] = getattr(importlib.import_module(module_name), attr)
    return factory()
