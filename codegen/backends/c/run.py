"""Run a generated C controller from Python: compile it to a shared library, call it by ctypes.

:class:`CompiledController` builds ``NAME_controller.c`` (and the fuzzy-PI's
``NAME_surface.c``) with the strict flags plus a small harness that is not part of the
generated code (``fuzzkit_controller_size``: the state's size; ``fuzzkit_controller_run``: n
periods in one call). Its ``step_function`` is ``NAME_controller_step`` itself, as a ctypes
function with ``argtypes`` set, and ``state`` a caller-owned ``NAME_controller_t`` (a byte
buffer of the right size), so a compiled loop can call the controller by address: pass
``step_function`` and ``ctypes.addressof(state)`` (or the buffer as an array) to numba, as
``fuzzkit.loop.compiled.generated_c`` does for a surface.
"""

from __future__ import annotations

import ctypes
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.codegen.toolchain import STRICT_FLAGS, cached_library

_CTYPE = {"float": ctypes.c_float, "double": ctypes.c_double}
_NUMPY = {"float": np.float32, "double": np.float64}


def harness_source(module: str, ctype: str) -> str:
    """C source of the batch helpers compiled next to the generated controller."""
    return f"""#include <stddef.h>
#include "{module}.h"

size_t fuzzkit_controller_size(void);
size_t fuzzkit_controller_size(void)
{{
    return sizeof({module}_t);
}}

void fuzzkit_controller_run({module}_t *c, const {ctype} *force, const {ctype} *rotation,
                            {ctype} *out, unsigned int *status, long n);
void fuzzkit_controller_run({module}_t *c, const {ctype} *force, const {ctype} *rotation,
                            {ctype} *out, unsigned int *status, long n)
{{
    long k;
    for (k = 0; k < n; k++) {{
        status[k] = (unsigned int){module}_step(c, force + 3 * k,
                                   rotation != NULL ? rotation + 9 * k : NULL, out + 3 * k);
    }}
}}
"""


class CompiledController:
    """A generated C controller compiled and loaded; the library stays mapped for the process.

    ``step(force_n, tool_rotation)`` -> ``(correction, status)`` one period at a time;
    ``run(forces, rotations)`` n periods in one call. ``reset()`` calls ``NAME_controller_reset``.
    """

    def __init__(
        self,
        files: Mapping[str, str],
        module: str,
        number_type: str,
        *,
        compiler: Sequence[str] | None = None,
        flags: Sequence[str] = (*STRICT_FLAGS, "-O2"),
    ) -> None:
        self.number_type = number_type
        ctype = _CTYPE[number_type]
        harness = {"fuzzkit_controller_harness.c": harness_source(module, number_type)}
        self.library: Any = cached_library(
            {**files, **harness}, module, compiler=compiler, flags=flags
        )
        ptr = ctypes.POINTER(ctype)
        size = self.library.fuzzkit_controller_size
        size.restype = ctypes.c_size_t
        size.argtypes = []
        #: the caller-owned NAME_controller_t (8-byte aligned: a double array)
        self.state: Any = (ctypes.c_double * ((int(size()) + 7) // 8))()
        self.init_function: Any = getattr(self.library, f"{module}_init")
        self.init_function.argtypes = [ctypes.c_void_p]
        self.init_function.restype = None
        self.reset_function: Any = getattr(self.library, f"{module}_reset")
        self.reset_function.argtypes = [ctypes.c_void_p]
        self.reset_function.restype = None
        #: ``uint32_t NAME_controller_step(state *, const T force[3], const T rot[9], T out[3])``
        self.step_function: Any = getattr(self.library, f"{module}_step")
        self.step_function.argtypes = [ctypes.c_void_p, ptr, ptr, ptr]
        self.step_function.restype = ctypes.c_uint32
        #: ``int NAME_controller_set_params(state *, const NAME_controller_params_t *)``
        self.set_params_function: Any = getattr(self.library, f"{module}_set_params")
        self.set_params_function.argtypes = [ctypes.c_void_p, ctypes.c_void_p]
        self.set_params_function.restype = ctypes.c_int
        #: ``void NAME_controller_adaptation(const state *, T factor[3], T k[3], int band[3])``
        #: (None: the spec does not adapt its gains)
        self.adaptation_function: Any = None
        if hasattr(self.library, f"{module}_adaptation"):
            self.adaptation_function = getattr(self.library, f"{module}_adaptation")
            self.adaptation_function.argtypes = [
                ctypes.c_void_p, ptr, ptr, ctypes.POINTER(ctypes.c_int)
            ]  # fmt: skip
            self.adaptation_function.restype = None
        self._run = self.library.fuzzkit_controller_run
        self._run.argtypes = [
            ctypes.c_void_p,
            ptr,
            ptr,
            ptr,
            ctypes.POINTER(ctypes.c_uint),
            ctypes.c_long,
        ]
        self._run.restype = None
        self._in = (ctype * 3)()
        self._rot = (ctype * 9)()
        self._out = (ctype * 3)()
        self.init_function(self.state)

    def reset(self) -> None:
        """``NAME_controller_reset`` on the state."""
        self.reset_function(self.state)

    def set_params(self, params: Sequence[float], state: Any = None) -> None:
        """``NAME_controller_set_params`` on ``state`` (default: this controller's) with
        ``params`` in :func:`params_vector` order.

        Raises
        ------
        ValueError
            The generated code refused them (a value it does not accept, see its header).
        """
        values = params_vector(params, self.number_type)
        if self.set_params_function(self.state if state is None else state, values) != 0:
            raise ValueError(f"the generated controller refused the parameters {list(params)}")

    def step(
        self, force_n: Sequence[float], tool_rotation: Sequence[float] | None = None
    ) -> tuple[list[float], int]:
        """One period: ``(correction_m, status)``."""
        for i in range(3):
            self._in[i] = force_n[i]
        rot = None
        if tool_rotation is not None:
            for i in range(9):
                self._rot[i] = tool_rotation[i]
            rot = self._rot
        status = int(self.step_function(self.state, self._in, rot, self._out))
        return [float(v) for v in self._out], status

    def adaptation(self, state: Any = None) -> tuple[list[float], list[float], list[int]]:
        """``NAME_controller_adaptation`` of ``state`` (default: this controller's): the gain
        factor, the stiffness estimate (N/mm) and the band per task axis.

        Raises
        ------
        ValueError
            The spec does not adapt its gains (the code has no such function).
        """
        if self.adaptation_function is None:
            raise ValueError("this generated controller does not adapt its gains")
        ctype = _CTYPE[self.number_type]
        factor, k, band = (ctype * 3)(), (ctype * 3)(), (ctypes.c_int * 3)()
        self.adaptation_function(self.state if state is None else state, factor, k, band)
        return [float(v) for v in factor], [float(v) for v in k], [int(v) for v in band]

    def run(
        self, forces: npt.ArrayLike, rotations: npt.ArrayLike | None = None
    ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]]:
        """``n`` periods from the current state: forces ``(n, 3)``, rotations ``(n, 9)`` or None.

        Returns the corrections ``(n, 3)`` (m) and the status of each period.
        """
        dtype = _NUMPY[self.number_type]
        ptr = ctypes.POINTER(_CTYPE[self.number_type])
        with np.errstate(over="ignore"):
            f = np.ascontiguousarray(np.asarray(forces, dtype=np.float64).astype(dtype))
        n = f.shape[0]
        if f.shape != (n, 3):
            raise ValueError(f"forces must have shape (n, 3), got {f.shape}")
        rot_ptr = None
        if rotations is not None:
            with np.errstate(over="ignore"):
                r = np.ascontiguousarray(np.asarray(rotations, dtype=np.float64).astype(dtype))
            if r.shape != (n, 9):
                raise ValueError(f"rotations must have shape ({n}, 9), got {r.shape}")
            rot_ptr = r.ctypes.data_as(ptr)
        out = np.empty((n, 3), dtype=dtype)
        status = np.zeros(n, dtype=np.uint32)
        self._run(
            self.state,
            f.ctypes.data_as(ptr),
            rot_ptr,
            out.ctypes.data_as(ptr),
            status.ctypes.data_as(ctypes.POINTER(ctypes.c_uint)),
            n,
        )
        return out.astype(np.float64), status.astype(np.int64)


#: The fields of ``NAME_controller_params_t`` in order: set points (3), kp (3), ki (3), kx (3),
#: correction_m, step_m.
PARAMS_LENGTH = 14


def params_vector(params: Sequence[float], number_type: str) -> Any:
    """``params`` (:data:`PARAMS_LENGTH` numbers) as a ``NAME_controller_params_t``."""
    if len(params) != PARAMS_LENGTH:
        raise ValueError(f"expected {PARAMS_LENGTH} parameters, got {len(params)}")
    return (_CTYPE[number_type] * PARAMS_LENGTH)(*params)


def open_controller(files: Mapping[str, str], module: str, number_type: str) -> CompiledController:
    """The C target's way to run a generated controller (``Target.open_controller``)."""
    return CompiledController(files, module, number_type)
