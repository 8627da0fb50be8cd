"""Artefacts built once per test run and shared by the pytest-xdist workers (not a test module).

``tests/conftest.py`` points ``$FUZZKIT_CACHE_DIR`` at one folder per run, shared by the
controller process and its workers: the package keeps compiled controllers and loop tables
there, and :func:`shared` keeps what the tests build themselves (lookup tables) beside them.
"""

from __future__ import annotations

import fcntl
import hashlib
import os
import pickle
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

T = TypeVar("T")

_LOADED: dict[str, object] = {}


def run_folder() -> Path:
    """This run's artefact folder (``$FUZZKIT_CACHE_DIR``, set by ``tests/conftest.py``)."""
    folder = os.environ.get("FUZZKIT_CACHE_DIR")
    if not folder:
        raise RuntimeError("FUZZKIT_CACHE_DIR is not set: tests/conftest.py sets it for a run")
    return Path(folder)


def shared(key: str, build: Callable[[], T]) -> T:
    """``build()``'s result, built by one process of the run and loaded by the others.

    ``key`` names the artefact by its content (for a table: the rule base's ``repr``, the
    number type, the resolution). The first process to ask builds it under a file lock while
    the others wait for it, then read it; each process keeps what it loaded. The folder is new
    for every run, so nothing built by older code is ever read.
    """
    digest = hashlib.sha256(key.encode()).hexdigest()[:32]
    if digest in _LOADED:
        return _LOADED[digest]  # type: ignore[return-value]
    folder = run_folder() / "tests"
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{digest}.pickle"
    with open(folder / f"{digest}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if path.is_file():
            value: T = pickle.loads(path.read_bytes())
        else:
            value = build()
            staged = path.with_suffix(f".{os.getpid()}.tmp")
            staged.write_bytes(pickle.dumps(value))
            os.replace(staged, path)  # a reader never sees half a file
    _LOADED[digest] = value
    return value
