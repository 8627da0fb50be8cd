"""Shared set-up of the test suite: kernels warmed once, artefacts built once per run."""

from __future__ import annotations

import os
from collections.abc import Iterator

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


# --------------------------------------------------------------------------------------------
# artefacts built once per run: compiled controllers, lookup tables, one Dask cluster


@pytest.fixture(scope="session", autouse=True)
def run_cache(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """``$FUZZKIT_CACHE_DIR`` for the whole run: one folder shared by the xdist workers.

    The package keeps compiled controllers (``controllers/``, keyed by their sources, the
    compiler and the version) and loop tables there, and ``_artefacts.shared`` the tables the
    tests build, so each is built once per run, not once per file and worker; a fresh folder
    per run means no test ever reads a stale user cache in ``~/.cache``. Tests of the caches
    themselves monkeypatch the variable to a folder of their own. Subprocesses the tests start
    (the CLI, doc commands) inherit it.
    """
    base = tmp_path_factory.getbasetemp()
    # a worker's basetemp is popen-gwN inside the controller's, which all workers share
    worker = os.environ.get("PYTEST_XDIST_WORKER")
    folder = (base.parent if worker else base) / "fuzzkit-cache"
    folder.mkdir(exist_ok=True)
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("FUZZKIT_CACHE_DIR", str(folder))
        yield str(folder)


@pytest.fixture(scope="session")
def dask_scheduler() -> Iterator[str]:
    """The address of one local Dask cluster for the run: two worker processes of one thread
    each (the tests check that two processes really ran), closed at the end."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        yield cluster.scheduler_address
