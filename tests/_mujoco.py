"""What the MuJoCo tests share: the compiled servo callback, and leaving no callback behind
(MuJoCo's control callback is process-global)."""

from __future__ import annotations

from collections.abc import Iterator

from fuzzkit.loop import mujoco as mujoco_plants
from fuzzkit.plants.mujoco_servo import ServoCallback


def servo() -> ServoCallback:
    """The servo callback ``--plant mujoco`` builds (a C compiler is needed)."""
    built = mujoco_plants.servo_callback()
    assert isinstance(built, ServoCallback), built
    return built


def uninstall_after() -> Iterator[None]:
    """A fixture body: the test, then MuJoCo's default (no control callback)."""
    yield
    ServoCallback.uninstall()
