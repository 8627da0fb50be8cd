"""A planar two-link arm in pymunk: the physics plant for closed-loop force-control tests.

The arm moves in the vertical x-z plane (pymunk's y axis is the world's z). It implements the
``fuzzkit.plants.contract.ContactPlant`` contract and knows nothing about fuzzy logic: a controller
is whoever calls :meth:`PlanarArmPlant.step`. :mod:`fuzzkit.planar_sim.arm_period` is the same
period as numba code around the same Chipmunk calls (:mod:`fuzzkit.planar_sim.chipmunk_calls`),
for the compiled closed loop.
"""

from fuzzkit.planar_sim.arm import (
    ArmParameters,
    PlanarArmPlant,
    forward_kinematics,
    inverse_kinematics,
)

__all__ = ["ArmParameters", "PlanarArmPlant", "forward_kinematics", "inverse_kinematics"]
