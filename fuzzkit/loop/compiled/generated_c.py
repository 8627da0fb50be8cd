"""The rule base's generated C, compiled and called through ctypes as a fuzzy-PI surface.

Lets a Python-loop run exercise the rule base's ``fuzzkit compile --target c --type double``
output (``fuzzkit.codegen.emit``), compiled with the system compiler
(``fuzzkit.codegen.toolchain``), called once per axis and period as ``NAME_eval`` through
:func:`c_surface` (``--fuzzy-impl c``).
"""

from __future__ import annotations

import ctypes
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

#: Compiled libraries stay loaded for the life of the process (one per rule base).
_LIBRARIES: list[Any] = []


@dataclass(frozen=True, slots=True)
class GeneratedC:
    """A rule base's generated double C, compiled and loaded: ``function`` is its ``NAME_eval``
    as a ctypes function (``argtypes`` two ``double *``, no result); ``label`` names it for a
    run's ``controller_impl``."""

    function: Any
    label: str


@lru_cache(maxsize=4)
def load_generated_c(rulebase: str = "macvicar_whelan", tolerance: float = 1e-3) -> GeneratedC:
    """Generate, compile and load the double C of ``rulebase`` at ``tolerance`` (the table of
    :func:`fuzzkit.loop.compiled.table.load_table`), once per process.

    Raises
    ------
    ToolchainError
        If no C compiler is found or the generated code does not compile.
    """
    from fuzzkit.codegen.emit import emit
    from fuzzkit.codegen.names import symbol
    from fuzzkit.codegen.toolchain import CompiledTable
    from fuzzkit.control.loop_rulebase import load_loop_rulebase
    from fuzzkit.loop.compiled.table import load_table

    rb = load_loop_rulebase(rulebase)
    table = load_table(rulebase, tolerance)
    files = emit(rb, table, "c")
    lib = CompiledTable(files, symbol(rb.name), "double", 2, 1, fpi=False)
    _LIBRARIES.append(lib)
    fn = getattr(lib.library, f"{symbol(rb.name)}_eval")
    fn.argtypes = [ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_double)]
    fn.restype = None
    return GeneratedC(fn, f"generated C {symbol(rb.name)}_eval (double, ctypes)")


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
    gen = load_generated_c(rulebase, tolerance)
    fn = gen.function
    inp = (ctypes.c_double * 2)()
    out = (ctypes.c_double * 1)()

    def surface(e: float, de: float) -> float:
        inp[0] = e
        inp[1] = de
        fn(inp, out)
        return float(out[0])

    surface.__name__ = gen.label
    return surface
