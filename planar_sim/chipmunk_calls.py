"""Calls into pymunk's Chipmunk library from numba-compiled code, by function address.

The compiled planar loop (:mod:`fuzzkit.planar_sim.arm_period`) makes the same Chipmunk calls as
:class:`fuzzkit.planar_sim.arm.PlanarArmPlant` (``cpSpaceStep``, ``cpBodyGetAngle``, ...), but from
inside one numba function. pymunk's cffi module keeps ``cpBody`` and friends opaque, and a
function address baked into compiled code would defeat numba's on-disk cache (the library loads
at another address in every process), so the addresses and object pointers travel as plain
integers (:func:`function_addresses`, :func:`pointer`) and the intrinsics below call through them.

The signatures are Chipmunk's, lowered as the C compiler lowers them on x86-64 and AArch64: a
``cpVect`` (two doubles) passed by value becomes two double arguments, and one returned comes
back as an LLVM ``{double, double}`` (two floating-point registers on both ABIs).
"""

from __future__ import annotations

import platform
from collections.abc import Callable
from typing import Any, cast

import numpy as np
import numpy.typing as npt
from llvmlite import ir
from numba import types
from numba.extending import intrinsic

IntArray = npt.NDArray[np.int64]

#: The Chipmunk functions the compiled loop calls, in the order of :func:`function_addresses`.
FUNCTIONS = (
    "cpSpaceStep",  # void (cpSpace *, double)
    "cpBodyGetAngle",  # double (cpBody *)
    "cpBodyGetPosition",  # cpVect (cpBody *)
    "cpBodyGetVelocity",  # cpVect (cpBody *)
    "cpSimpleMotorSetRate",  # void (cpConstraint *, double)
    "cpConstraintGetImpulse",  # double (cpConstraint *)
    "cpBodyApplyForceAtWorldPoint",  # void (cpBody *, cpVect, cpVect)
)
F_SPACE_STEP, F_GET_ANGLE, F_GET_POSITION, F_GET_VELOCITY = 0, 1, 2, 3
F_MOTOR_SET_RATE, F_GET_IMPULSE, F_APPLY_FORCE = 4, 5, 6

#: Machines whose C calling convention the intrinsics' lowering is known to match.
SUPPORTED_MACHINES = ("x86_64", "AMD64", "aarch64", "arm64")


def calls_supported() -> bool:
    """True where the compiled loop may call Chipmunk directly (see the module docstring)."""
    return platform.machine() in SUPPORTED_MACHINES


def function_addresses() -> IntArray:
    """The addresses of :data:`FUNCTIONS` in pymunk's loaded Chipmunk library."""
    from pymunk._chipmunk import ffi, lib

    return np.array(
        [int(ffi.cast("uintptr_t", ffi.addressof(lib, name))) for name in FUNCTIONS],
        dtype=np.int64,
    )


def pointer(cdata: Any) -> int:
    """The address of a pymunk object's Chipmunk struct (``body._body``, ``space._space``, ...)."""
    from pymunk._chipmunk import ffi

    return int(ffi.cast("uintptr_t", cdata))


_f64 = ir.DoubleType()
_ptr = ir.IntType(8).as_pointer()
_vec = ir.LiteralStructType([_f64, _f64])


def _call(builder: ir.IRBuilder, fnty: ir.FunctionType, addr: ir.Value, *args: ir.Value) -> Any:
    fn = builder.inttoptr(addr, fnty.as_pointer())
    return builder.call(fn, args)


def _call_v_pd(typingctx: Any, addr: Any, obj: Any, x: Any) -> Any:
    """``void f(void *obj, double x)`` at ``addr``."""
    sig = types.none(types.int64, types.int64, types.float64)

    def codegen(context: Any, builder: ir.IRBuilder, signature: Any, args: Any) -> Any:
        fnty = ir.FunctionType(ir.VoidType(), [_ptr, _f64])
        _call(builder, fnty, args[0], builder.inttoptr(args[1], _ptr), args[2])
        return context.get_dummy_value()

    return sig, codegen


def _call_d_p(typingctx: Any, addr: Any, obj: Any) -> Any:
    """``double f(void *obj)`` at ``addr``."""
    sig = types.float64(types.int64, types.int64)

    def codegen(context: Any, builder: ir.IRBuilder, signature: Any, args: Any) -> Any:
        fnty = ir.FunctionType(_f64, [_ptr])
        return _call(builder, fnty, args[0], builder.inttoptr(args[1], _ptr))

    return sig, codegen


def _call_vec_p(typingctx: Any, addr: Any, obj: Any) -> Any:
    """``cpVect f(void *obj)`` at ``addr``, returned as ``(x, y)``."""
    sig = cast(Any, types.UniTuple)(types.float64, 2)(types.int64, types.int64)

    def codegen(context: Any, builder: ir.IRBuilder, signature: Any, args: Any) -> Any:
        fnty = ir.FunctionType(_vec, [_ptr])
        v = _call(builder, fnty, args[0], builder.inttoptr(args[1], _ptr))
        x = builder.extract_value(v, 0)
        y = builder.extract_value(v, 1)
        return context.make_tuple(builder, signature.return_type, (x, y))

    return sig, codegen


def _call_v_pvv(typingctx: Any, addr: Any, obj: Any, ax: Any, ay: Any, bx: Any, by: Any) -> Any:
    """``void f(void *obj, cpVect a, cpVect b)`` at ``addr``."""
    sig = types.none(
        types.int64, types.int64, types.float64, types.float64, types.float64, types.float64
    )

    def codegen(context: Any, builder: ir.IRBuilder, signature: Any, args: Any) -> Any:
        fnty = ir.FunctionType(ir.VoidType(), [_ptr, _f64, _f64, _f64, _f64])
        _call(builder, fnty, args[0], builder.inttoptr(args[1], _ptr), *args[2:])
        return context.get_dummy_value()

    return sig, codegen


# Typed for mypy as what they are to numba code: functions of integers and floats.
call_v_pd = cast(Callable[[int, int, float], None], intrinsic(_call_v_pd))
call_d_p = cast(Callable[[int, int], float], intrinsic(_call_d_p))
call_vec_p = cast(Callable[[int, int], tuple[float, float]], intrinsic(_call_vec_p))
call_v_pvv = cast(Callable[[int, int, float, float, float, float], None], intrinsic(_call_v_pvv))
