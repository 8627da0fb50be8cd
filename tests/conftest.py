"""Shared set-up of the test suite."""

from __future__ import annotations

from typing import Any

import pytest

# --------------------------------------------------------------------------------------------
# numba kernels, compiled once before the xdist workers use them

#: The controller's background warm-up (:class:`fuzzkit.studies.compiled.warm.Warming`).
_WARMING: pytest.StashKey[Any] = pytest.StashKey()


def _several_workers(config: pytest.Config) -> bool:
    workers = getattr(config.option, "numprocesses", None)
    return isinstance(workers, int) and workers > 1


def pytest_sessionstart(session: pytest.Session) -> None:
    """In the controller process of a run with more than one xdist worker, start warming every
    numba kernel in the background, in as many processes as workers (the workers start and
    collect meanwhile, then wait for it in :func:`pytest_collection_finish`): each worker
    then loads the kernels from numba's disk cache instead of compiling them again. A run
    without workers (no ``-n``, ``-n 0``) or with one pays nothing here; its first use
    compiles what it needs, as before."""
    config = session.config
    if hasattr(config, "workerinput") or config.option.collectonly:
        return
    if _several_workers(config):
        from fuzzkit.studies.compiled.warm import warm, warm_in_background

        warming = warm_in_background(config.option.numprocesses)
        if warming is None:  # no flock here: warm before the workers start
            _report_failure(config, _call(warm))
        config.stash[_WARMING] = warming


def _call(fn: Any) -> str | None:
    try:
        fn()
    except Exception as exc:
        return f"{type(exc).__name__}: {exc}"
    return None


def pytest_collection_finish(session: pytest.Session) -> None:
    """A worker waits here, after collecting, for the controller's warm-up to finish."""
    if hasattr(session.config, "workerinput"):
        from fuzzkit.studies.compiled.warm import wait_for_warming

        wait_for_warming()


def pytest_sessionfinish(session: pytest.Session) -> None:
    """The controller reports a warm-up that failed, in one line (a broken kernel fails the
    tests that use it, by name: the workers compile it, and fail, on first use)."""
    warming = session.config.stash.get(_WARMING, None)
    if warming is not None:
        _report_failure(session.config, warming.finish())


def _report_failure(config: pytest.Config, why: str | None) -> None:
    reporter = config.pluginmanager.get_plugin("terminalreporter")
    if why is not None and reporter is not None:
        reporter.write_line(f"kernel warm-up failed ({why})")
