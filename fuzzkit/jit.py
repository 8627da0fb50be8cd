"""The one numba entry point of fuzzkit: ``jit`` compiles a function in nopython mode, cached.

Compiled code is cached on disk next to the module (numba ``cache=True``), so only the very first
call after an install (or a change of the source) pays the compilation; later processes load it.
Kept typed here so that ``mypy --strict`` sees through the decorator.

numba stamps a cached kernel with the content of the kernel's own source file only, so an edit to
a compiled function it calls in another module (``studies/compiled/period.py`` called from
``arm6_run.py``) would silently load the stale kernel. fuzzkit's kernels are therefore stamped
with a fingerprint of every fuzzkit source file as well (:func:`source_fingerprint`, read once
per process): any edit to the package recompiles them, and nothing else's cache is touched.

Ctrl-C is held while numba compiles or loads a kernel (numba's compiler lock is
held): a KeyboardInterrupt raised inside the compiler corrupts LLVM's memory. See
:func:`fuzzkit.progress.interrupt_shield`; the listener below is numba's documented event API.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.util
import os
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any, TypeVar, cast

import numba
from numba.core import caching, event

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


#: The folders of the installed package: ``fuzzkit/`` and the folders mapped into it.
_MAPPED = ("fuzzkit.codegen", "fuzzkit.planar_sim")


def package_roots() -> list[Path]:
    """The source folders of the installed package (``fuzzkit`` and its mapped folders)."""
    roots = [Path(__file__).resolve().parent]
    for name in _MAPPED:
        spec = importlib.util.find_spec(name)
        for location in (spec.submodule_search_locations or []) if spec is not None else []:
            roots.append(Path(location).resolve())
    return roots


def fingerprint_of(roots: Iterable[Path]) -> str:
    """sha256 over the relative path and content of every ``.py`` file under ``roots``."""
    digest = hashlib.sha256()
    for root in roots:
        for path in sorted(root.rglob("*.py")):
            digest.update(path.relative_to(root).as_posix().encode("utf-8") + b"\0")
            digest.update(path.read_bytes() + b"\0")
    return digest.hexdigest()


@functools.cache
def source_fingerprint() -> str:
    """The fingerprint of this installation's sources (:func:`fingerprint_of` its roots)."""
    return fingerprint_of(package_roots())


def _in_package(py_file: str) -> bool:
    path = Path(os.path.abspath(py_file))
    return any(path.is_relative_to(root) for root in package_roots())


class _PackageStamp:
    """Locator mixin: valid for a fuzzkit source file, stamped with the whole package's
    fingerprint besides numba's own stamp of the file."""

    def get_source_stamp(self) -> Any:
        return (super().get_source_stamp(), source_fingerprint())  # type: ignore[misc]

    @classmethod
    def from_function(cls, py_func: Any, py_file: str) -> Any:
        if not _in_package(py_file):
            return None
        return super().from_function(py_func, py_file)  # type: ignore[misc]


def _install_locators() -> None:
    """Put the package-stamped twins of numba's source-file locators first (once), in numba's
    order: a user-provided ``NUMBA_CACHE_DIR``, the module's ``__pycache__``, the user cache."""
    # numba 0.68 made the names public; older releases keep the underscore
    impl: Any = getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl")  # noqa: B009
    if any(issubclass(c, _PackageStamp) for c in impl._locator_classes):
        return
    ours = []
    for name in ("UserProvidedCacheLocator", "InTreeCacheLocator", "UserWideCacheLocator"):
        base = getattr(caching, name, None) or getattr(caching, "_" + name)
        ours.append(type("Fuzzkit" + name, (_PackageStamp, base), {}))
    impl._locator_classes = ours + list(impl._locator_classes)


_install_locators()


def jit(fn: F) -> F:
    """Compile ``fn`` with ``numba.njit(cache=True)``: nopython, cached on disk, errors at call."""
    return cast(F, numba.njit(cache=True)(fn))
