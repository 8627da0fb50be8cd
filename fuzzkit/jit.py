"""The one numba entry point of fuzzkit: ``jit`` compiles a function in nopython mode, cached.

Compiled code is cached on disk next to the module (numba ``cache=True``), so only the very first
call after an install (or a change of the source) pays the compilation; later processes load it.
Kept typed here so that ``mypy --strict`` sees through the decorator.

numba stamps a cached kernel with the content of the kernel's own source file only, so an edit to
a compiled function it calls in another module (``loop/compiled/period.py`` called from
``arm6_run.py``), or to a constant it reads from one, would silently load the stale kernel.
fuzzkit's kernels are therefore stamped with the digest of their module's import closure
instead (:class:`fuzzkit.import_closure.ImportGraph`: every package module the kernel's module
binds names from, transitively, its own file included): an edit to a module the kernel can
reach recompiles it, an edit anywhere else (the CLI, the viewers, the docs) does not. The
closures are computed once per module per process, and nothing else's cache is touched.

Ctrl-C is held while numba compiles or loads a kernel (numba's compiler lock is
held): a KeyboardInterrupt raised inside the compiler corrupts LLVM's memory. See
:func:`fuzzkit.progress.interrupt_shield`; the listener below is numba's documented event API.
"""

from __future__ import annotations

import functools
import importlib.util
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar, cast

import numba
from numba.core import caching, event

from fuzzkit.import_closure import ImportGraph
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


#: The packages mapped into fuzzkit from their own repository folders (``setup.py``).
_MAPPED = ("fuzzkit.codegen", "fuzzkit.planar_sim")


def package_roots() -> dict[str, Path]:
    """The source folder of ``fuzzkit`` and of each package mapped into it, by package name."""
    roots = {"fuzzkit": Path(__file__).resolve().parent}
    for name in _MAPPED:
        spec = importlib.util.find_spec(name)
        for location in (spec.submodule_search_locations or []) if spec is not None else []:
            roots[name] = Path(location).resolve()
    return roots


@functools.cache
def package_graph() -> ImportGraph:
    """The import graph of this installation's sources, shared by every kernel of the process
    (its parses kept on disk for the next process)."""
    return ImportGraph(package_roots(), keep=True)


class _ClosureStamp:
    """Locator mixin: serves a kernel whose source is a package module, stamped with the digest
    of that module's import closure (in place of numba's stamp of the one file)."""

    _fuzzkit_module: str

    def get_source_stamp(self) -> Any:
        return package_graph().digest(self._fuzzkit_module)

    @classmethod
    def from_function(cls, py_func: Any, py_file: str) -> Any:
        module = package_graph().module_of(Path(py_file))
        if module is None:
            return None
        locator = super().from_function(py_func, py_file)  # type: ignore[misc]
        if locator is not None:
            locator._fuzzkit_module = module
        return locator


def _install_locators() -> None:
    """Put the closure-stamped twins of numba's source-file locators first (once), in numba's
    order: a user-provided ``NUMBA_CACHE_DIR``, the module's ``__pycache__``, the user cache."""
    # numba 0.68 made the names public; older releases keep the underscore
    impl: Any = getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl")  # noqa: B009
    if any(issubclass(c, _ClosureStamp) for c in impl._locator_classes):
        return
    ours = []
    for name in ("UserProvidedCacheLocator", "InTreeCacheLocator", "UserWideCacheLocator"):
        base = getattr(caching, name, None) or getattr(caching, "_" + name)
        ours.append(type("Fuzzkit" + name, (_ClosureStamp, base), {}))
    impl._locator_classes = ours + list(impl._locator_classes)


_install_locators()


def jit(fn: F) -> F:
    """Compile ``fn`` with ``numba.njit(cache=True)``: nopython, cached on disk, errors at call."""
    return cast(F, numba.njit(cache=True)(fn))


def jit_inline(fn: F) -> F:
    """:func:`jit`, and inlined into the compiled code that calls it (numba's
    ``inline="always"``, at numba's IR level; Python still calls it as a kernel).

    For the small helpers every period of a compiled loop calls: a call that numba does not
    inline costs an atomic reference count on every array passed through it, in and out,
    which for the loop's helpers cost more than their own arithmetic (docs/benchmarks.md)."""
    return cast(F, numba.njit(cache=True, inline="always")(fn))


def has_cached_code(kernel: Any) -> bool:
    """True when ``kernel`` (a function compiled by :func:`jit`) has machine code in its disk
    cache for the current sources: its index file is there, current (stamp and numba version)
    and not empty. The next process to call it with those argument types loads instead of
    compiling."""
    return bool(kernel._cache._cache_file._load_index())
