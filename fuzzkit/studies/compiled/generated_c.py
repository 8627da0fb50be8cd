"""The rule base's generated C, compiled and called through ctypes as a fuzzy-PI surface.

Lets a closed-loop run exercise the very code that goes on the robot: ``fuzzkit compile
--target c --type double`` output (``fuzzkit.codegen.emit``), compiled with the system compiler
(``fuzzkit.codegen.toolchain``), called once per axis and period as ``NAME_eval``.
"""

from __future__ import annotations

import ctypes
from collections.abc import Callable
from functools import lru_cache
from typing import Any

from fuzzkit.studies.compiled.loop import load_table

#: Compiled libraries stay loaded for the life of the process (one per rule base).
_LIBRARIES: list[Any] = []


@lru_cache(maxsize=4)
def c_surface(
    rulebase: str = "macvicar_whelan", tolerance: float = 1e-3
) -> Callable[[float, float], float]:
    """``(e, de) -> du`` calling the generated double C of ``rulebase`` (its ``NAME_eval``).

    Raises
    ------
    ToolchainError
        If no C compiler is found or the generated code does not compile.
    """
    from fuzzkit.codegen.emit import emit
    from fuzzkit.codegen.toolchain import CompiledTable
    from fuzzkit.formats.registry import load

    rb = load(rulebase)
    table = load_table(rulebase, tolerance)
    files = emit(rb, table, "c")
    lib = CompiledTable(files, rb.name, "double", 2, 1, fpi=False)
    _LIBRARIES.append(lib)
    fn = getattr(lib.library, f"{rb.name}_eval")
    fn.argtypes = [ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_double)]
    fn.restype = None
    inp = (ctypes.c_double * 2)()
    out = (ctypes.c_double * 1)()

    def surface(e: float, de: float) -> float:
        inp[0] = e
        inp[1] = de
        fn(inp, out)
        return float(out[0])

    surface.__name__ = f"generated C {rb.name}_eval (double, ctypes)"
    return surface
