"""The MuJoCo plants' adapters: the IRB 140 in MuJoCo (``mujoco``) and with joint springs
(``mujoco-elastic``). No compiled loop yet: the Python loop runs them, with the run's generated
controller. The factories import MuJoCo only when a plant is built."""

from __future__ import annotations

from fuzzkit.loop.adapter import PlantAdapter
from fuzzkit.plants.contract import ContactPlant


def _arm() -> ContactPlant:
    from fuzzkit.plants.mujoco_arm import MujocoArmPlant

    return MujocoArmPlant()


def _elastic() -> ContactPlant:
    from fuzzkit.plants.mujoco_arm import ElasticMujocoArmPlant

    return ElasticMujocoArmPlant()


ADAPTER = PlantAdapter("mujoco", _arm)
ELASTIC = PlantAdapter("mujoco-elastic", _elastic)
