"""The one numba entry point of fuzzkit: ``jit`` compiles a function in nopython mode, cached.

Compiled code is cached on disk next to the module (numba ``cache=True``), so only the very first
call after an install (or a change of the source) pays the compilation; later processes load it.
Kept typed here so that ``mypy --strict`` sees through the decorator.

Ctrl-C is held while numba compiles or loads a kernel (numba's compiler lock is
held): a KeyboardInterrupt raised inside the compiler corrupts LLVM's memory. See
:func:`fuzzkit.progress.interrupt_shield`; the listener below is numba's documented event API.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar, cast

import numba
from numba.core import event

from fuzzkit.progress import enter_interrupt_shield, leave_interrupt_shield

F = TypeVar("F", bound=Callable[..., Any])
#: numba's event for "the compiler is running": its compiler lock, taken around every compile
#: and cache load. Its end is broadcast after the lock is released, so a held Ctrl-C delivered
#: there cuts nothing. (Not ``numba:llvm_lock``: llvmlite broadcasts that one's end *before*
#: releasing its lock, which a KeyboardInterrupt there would leave held.)
COMPILER_EVENTS = ("numba:compiler_lock",)


class _ShieldWhileCompiling(event.Listener):
    """Holds Ctrl-C from the start of a compiler event to its end (nested events count)."""

    def on_start(self, ev: event.Event) -> None:
        enter_interrupt_shield()

    def on_end(self, ev: event.Event) -> None:
        leave_interrupt_shield()


_SHIELD = _ShieldWhileCompiling()
for _kind in COMPILER_EVENTS:
    event.register(_kind, _SHIELD)  # type: ignore[no-untyped-call]


def jit(fn: F) -> F:
    """Compile ``fn`` with ``numba.njit(cache=True)``: nopython, cached on disk, errors at call."""
    return cast(F, numba.njit(cache=True)(fn))
