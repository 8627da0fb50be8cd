"""Shared set-up of the test suite."""

from __future__ import annotations

import pytest

# --------------------------------------------------------------------------------------------
# numba kernels, compiled once before the xdist workers start


def pytest_sessionstart(session: pytest.Session) -> None:
    """Compile or load every numba kernel in the controller process of a run with more than
    one xdist worker, before the workers start (xdist starts them in its own, later
    ``pytest_sessionstart``): each worker then loads the kernels from numba's disk cache
    instead of compiling them again. A run without workers (no ``-n``, ``-n 0``) or with one
    pays nothing here; its first use compiles what it needs, as before. A warm-up that fails
    is reported in one line and the session goes on."""
    config = session.config
    if hasattr(config, "workerinput") or config.option.collectonly:
        return
    workers = getattr(config.option, "numprocesses", None)
    if isinstance(workers, int) and workers > 1:
        from fuzzkit.studies.compiled.warm import warm

        try:
            warm()
        except Exception as exc:
            # a broken kernel must fail the tests that use it, by name, not stop the session
            # before any test ran; the workers compile (and fail) on first use as without warming
            reporter = config.pluginmanager.get_plugin("terminalreporter")
            if reporter is not None:
                reporter.write_line(f"kernel warm-up failed ({type(exc).__name__}: {exc})")
