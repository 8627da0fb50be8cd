"""A planar two-link arm in pymunk: the physics plant for closed-loop force-control tests.

The arm moves in the vertical x-z plane (pymunk's y axis is the world's z). It implements the
``fuzzkit.plants.contract.ContactPlant`` contract and knows nothing about fuzzy logic: a controller
is whoever calls :meth:`PlanarArmPlant.step`. :mod:`fuzzkit.planar_sim.arm_period` is the same
period as numba code around the same Chipmunk calls (:mod:`fuzzkit.planar_sim.chipmunk_calls`),
for the compiled closed loop.
"""

if __name__ != "fuzzkit.planar_sim":  # this repository folder imported as a top-level package
    raise ImportError(
        f"{__name__!r} is the source folder of fuzzkit.planar_sim; import fuzzkit.planar_sim "
        "(pip install -e . maps this folder into fuzzkit)"
    )

from fuzzkit.planar_sim.arm import (
    ArmParameters,
    PlanarArmPlant,
    forward_kinematics,
    inverse_kinematics,
)

__all__ = ["ArmParameters", "PlanarArmPlant", "forward_kinematics", "inverse_kinematics"]
