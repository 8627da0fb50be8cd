"""The plants a study can run on, by name (:data:`PLANTS`): ``planar`` (pymunk), ``arm6``
(6-DOF kinematic), ``mujoco`` and ``mujoco-elastic`` (6-DOF dynamic, MuJoCo)."""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass

from fuzzkit.errors import ConfigError
from fuzzkit.plants.contract import ContactPlant


@dataclass(frozen=True)
class PlantEntry:
    """A plant of the registry: ``"module:factory"`` (the factory takes no arguments and
    returns a ContactPlant) and what the plant is, as ``--plant`` help lists it."""

    factory: str
    summary: str


#: Plant name -> its entry. Imported lazily so that choosing one plant never imports another's
#: dependencies.
PLANTS: dict[str, PlantEntry] = {
    "planar": PlantEntry("fuzzkit.planar_sim:PlanarArmPlant", "pymunk planar two-link arm"),
    "arm6": PlantEntry("fuzzkit.plants.arm6:Arm6Plant", "6-DOF IRB 140, kinematic"),
    "mujoco": PlantEntry(
        "fuzzkit.studies.mujoco_plants:mujoco_plant", "the IRB 140 in MuJoCo, dynamic"
    ),
    "mujoco-elastic": PlantEntry(
        "fuzzkit.studies.mujoco_plants:elastic_mujoco_plant",
        "the MuJoCo IRB 140 with joint springs",
    ),
}


def plants_text() -> str:
    """Every plant of the registry with what it is: ``arm6 (6-DOF IRB 140, kinematic), ...``."""
    return ", ".join(f"{name} ({entry.summary})" for name, entry in sorted(PLANTS.items()))


def make_plant(name: str) -> ContactPlant:
    """Build the plant registered as ``name`` (see :data:`PLANTS`)."""
    entry = PLANTS.get(name)
    if entry is None:
        raise ConfigError(f"unknown plant {name!r} (expected one of {', '.join(sorted(PLANTS))})")
    module_name, _, attr = entry.factory.partition(":")
    factory: Callable[[], ContactPlant] = getattr(importlib.import_module(module_name), attr)
    return factory()
