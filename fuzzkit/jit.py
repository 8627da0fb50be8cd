"""The one numba entry point of fuzzkit: ``jit`` compiles a function in nopython mode, cached.

Compiled code is cached on disk next to the module (numba ``cache=True``), so only the very first
call after an install (or a change of the source) pays the compilation; later processes load it.
Kept typed here so that ``mypy --strict`` sees through the decorator.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar, cast

import numba

F = TypeVar("F", bound=Callable[..., Any])


def jit(fn: F) -> F:
    """Compile ``fn`` with ``numba.njit(cache=True)``: nopython, cached on disk, errors at call."""
    return cast(F, numba.njit(cache=True)(fn))
