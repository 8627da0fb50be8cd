"""The MuJoCo arm's servo reference ramp as a C control callback (``mjcb_control``).

Every physics substep of a period the servos' controls follow the reference ramp
``prev + (s / n) (ref - prev) + feed`` (:meth:`fuzzkit.plants.mujoco_arm.MujocoArmPlant.step`).
In Python that is one ``mj_step`` call per substep with the ramp between them; with the callback
(``mujoco_servo.c`` beside this module, compiled by the kit's toolchain above this layer and
handed to the plant, :meth:`~fuzzkit.plants.mujoco_arm.MujocoArmPlant.use_servo_callback`) MuJoCo
computes the ramp itself, and a period is one ``mj_step(m, d, nstep=n)``. The Python ramp stays
the reference: ``tests/test_mujoco_servo.py`` holds the two to the same trajectory, bit for bit.

The callback's state is per ``MjData``, in ``d.userdata`` (:data:`USERDATA_HEAD` values, then
``prev``, ``ref``, ``feed``, ``limit`` and ``saturated``, ``nu`` values each): the model reserves
:func:`userdata_size` of it (``<size nuserdata>``), and data not armed by :meth:`ServoCallback.arm`
are left alone by the callback, so one process-global callback serves every simulation of every
thread. This module knows no compiler: it takes the loaded library.
"""

from __future__ import annotations

import ctypes
from collections.abc import Callable
from importlib import resources
from typing import Any

import mujoco
import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]

#: ``d.userdata`` header, as ``mujoco_servo.c`` reads it (its ``FK_SERVO_*`` macros)
U_MARK, U_SUBSTEP, U_NSUB, U_NU = 0, 1, 2, 3
USERDATA_HEAD = 4
#: the header's first value when the data are armed (``FK_SERVO_MARK_VALUE``)
MARK = 46553.0
#: arrays after the header, ``nu`` values each: prev, ref, feed, limit, saturated
_ARRAYS = 5

#: the callback's C source file, beside this module
SOURCE = "mujoco_servo.c"


def source_text() -> str:
    """The callback's C source (``mujoco_servo.c``, package data)."""
    return resources.files(__package__).joinpath(SOURCE).read_text(encoding="utf-8")


def userdata_size(nu: int) -> int:
    """``nuserdata`` the model needs for ``nu`` actuators."""
    return USERDATA_HEAD + _ARRAYS * nu


class ServoCallback:
    """The compiled ramp (``fuzzkit_servo_ramp`` of a loaded ``mujoco_servo.c`` library): arms an
    ``MjData``, installs itself as MuJoCo's control callback, and steps one period.

    Raises
    ------
    RuntimeError
        If the library was compiled against another MuJoCo version's headers than the one
        loaded (its ``mjData`` layout may differ).
    """

    def __init__(self, library: Any) -> None:
        version = int(library.fuzzkit_servo_mj_version())
        if version != mujoco.mj_version():
            raise RuntimeError(
                f"the servo callback was compiled against MuJoCo {version}'s headers, "
                f"but MuJoCo {mujoco.mj_version()} is loaded"
            )
        self.library = library
        self.function = library.fuzzkit_servo_ramp
        address = ctypes.c_uint64  # an MjModel's or MjData's ``_address``
        #: ``fuzzkit_mj_steps(model, data, n)``: n physics steps, the bad-acceleration
        #: warnings among them (for a loop compiled around MuJoCo: no Python per period)
        self.steps = library.fuzzkit_mj_steps
        self.steps.argtypes = [address, address, ctypes.c_int]
        self.steps.restype = ctypes.c_int
        #: ``fuzzkit_tool_contacts(model, data, tip, total, normals, points, most)``: the
        #: plant's contact-force sum (``MujocoArmPlant._contact_force``) in C
        self.contacts = library.fuzzkit_tool_contacts
        self.contacts.argtypes = [address, address, ctypes.c_int, *(ctypes.c_void_p,) * 3,
                                  ctypes.c_int]  # fmt: skip
        self.contacts.restype = ctypes.c_int
        #: ``fuzzkit_servo_mark_last(model, data)``: the last substep's torque limits marked
        self.mark_last = library.fuzzkit_servo_mark_last
        self.mark_last.argtypes = [address, address]
        self.mark_last.restype = None

    def install(self) -> None:
        """Make the ramp MuJoCo's control callback (process-global; the binding keeps the C
        pointer, so MuJoCo calls it without the GIL)."""
        mujoco.set_mjcb_control(self.function)

    @staticmethod
    def uninstall() -> None:
        """No control callback (tests restore MuJoCo's default with it)."""
        mujoco.set_mjcb_control(None)

    @staticmethod
    def arm(d: mujoco.MjData, n_sub: int, limits: FloatArray) -> FloatArray:
        """Mark ``d`` for the callback: ``n_sub`` substeps per period, the actuators' force
        ``limits``; returns the userdata view :meth:`period` writes."""
        nu = len(limits)
        u: FloatArray = d.userdata
        if len(u) < userdata_size(nu):
            raise RuntimeError(
                f"the model reserves {len(u)} userdata values; the servo callback needs "
                f"{userdata_size(nu)} (<size nuserdata>)"
            )
        u[:] = 0.0
        u[U_NSUB], u[U_NU] = float(n_sub), float(nu)
        u[USERDATA_HEAD + 3 * nu : USERDATA_HEAD + 4 * nu] = limits
        u[U_MARK] = MARK
        return u

    def period(
        self,
        m: mujoco.MjModel,
        d: mujoco.MjData,
        u: FloatArray,
        prev: FloatArray,
        ref: FloatArray,
        feed: FloatArray,
        before_substep: Callable[[], None] | None = None,
    ) -> npt.NDArray[np.bool_]:
        """One period: the ramp's ends and feed-forward into ``u`` (from :meth:`arm`), then the
        period's substeps, in one ``mj_step`` call, or one call per substep after
        ``before_substep`` (which moves mocap bodies); returns which actuators reached 99.9 %
        of their force limit in any substep."""
        nu = len(prev)
        h = USERDATA_HEAD
        u[U_SUBSTEP] = 0.0
        u[h : h + nu] = prev
        u[h + nu : h + 2 * nu] = ref
        u[h + 2 * nu : h + 3 * nu] = feed
        saturated = u[h + 4 * nu : h + 5 * nu]
        saturated[:] = 0.0
        n_sub = int(u[U_NSUB])
        if before_substep is None:
            mujoco.mj_step(m, d, nstep=n_sub)
        else:
            for _ in range(n_sub):
                before_substep()
                mujoco.mj_step(m, d)
        # the callback marks each substep's forces before the next one; the last ones here
        self.mark_last(m._address, d._address)
        marked: npt.NDArray[np.bool_] = saturated != 0.0
        return marked
