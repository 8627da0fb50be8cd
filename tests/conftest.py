"""Shared set-up of the test suite: kernels warmed once, artefacts built once per run."""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from _dispatch import pin_kernels

pin_kernels()  # before numpy's first import: one set of floating-point kernels on every CPU

# --------------------------------------------------------------------------------------------
# numba kernels, compiled once before the xdist workers use them

#: The controller's background warm-up (:class:`fuzzkit.studies.warm.Warming`).
_WARMING: pytest.StashKey[Any] = pytest.StashKey()


def _several_workers(config: pytest.Config) -> bool:
    workers = getattr(config.option, "numprocesses", None)
    return isinstance(workers, int) and workers > 1


def pytest_sessionstart(session: pytest.Session) -> None:
    """In the controller process of a run with more than one xdist worker, start warming every
    numba kernel in the background, in as many processes as workers (the workers start and
    collect meanwhile, then wait for it in :func:`pytest_collection_finish`): each worker
    then loads the kernels from numba's disk cache instead of compiling them again. When a warm-up
    started before pytest is named by ``FUZZKIT_WARM_LOCK`` (``make test`` starts one while its
    static checks run), these processes wait for it first and find its kernels cached. A run
    without workers (no ``-n``, ``-n 0``) or with one pays nothing here; its first use
    compiles what it needs, as before."""
    config = session.config
    if hasattr(config, "workerinput") or config.option.collectonly:
        return
    if _several_workers(config):
        from fuzzkit.studies.warm import warm, warm_in_background

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


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """The tests marked ``slow`` first, each group in its own order: xdist hands the tests to
    the workers in this order, so the long ones are spread over the run and the short ones
    fill in at the end, instead of one worker finishing a long doc command or report alone."""
    items.sort(key=lambda item: item.get_closest_marker("slow") is None)


def pytest_collection_finish(session: pytest.Session) -> None:
    """A worker waits here, after collecting, for the controller's warm-up to finish."""
    if hasattr(session.config, "workerinput"):
        from fuzzkit.studies.warm import wait_for_warming

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


# --------------------------------------------------------------------------------------------
# artefacts built once per run: compiled controllers, lookup tables, one Dask cluster, the
# built wheel and sdist


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
    each (the tests check that two processes really ran), on free ports, closed at the end.
    A session fixture is one per xdist worker: the tests that use it are marked
    ``xdist_group("dask")``, and ``make test`` runs ``--dist loadgroup``, so that they share
    one worker and one cluster."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
    ) as cluster:
        yield cluster.scheduler_address


@pytest.fixture(scope="session")
def built_dists() -> Callable[[bool], tuple[Path, Path]]:
    """``built_dists(release)``: the (wheel, sdist) built from a clean copy of the repository,
    the release build (isolated) or the quick one; each kind is built once per run, by the
    first worker that asks, and read by the other (``tests/_dists.py``)."""
    from _artefacts import run_folder, shared
    from _dists import build_dists

    def get(release: bool) -> tuple[Path, Path]:
        kind = "release" if release else "quick"
        return shared(f"dists:{kind}", lambda: build_dists(release, run_folder() / "dists"))

    return get


# --------------------------------------------------------------------------------------------
# compile --target python --verify in the CLI tests

#: How many points `make test`'s CLI tests of ``compile --target python --verify`` check: the
#: pure-Python module takes about 150 us a point, so the default 100,000 cost 16 s a call; the
#: same tests at the default count run in `make verify`.
COVER_VERIFY_POINTS = 5_000


@pytest.fixture(
    params=[
        pytest.param(COVER_VERIFY_POINTS, id="cover-points"),
        pytest.param(None, id="full-points", marks=pytest.mark.verify),
    ]
)
def python_verify_points(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> None:
    """``compile --target python --verify`` checks :data:`COVER_VERIFY_POINTS` points (in
    `make verify`: the default, ``fuzzkit.codegen.verify.DEFAULT_POINTS``), by the same
    verification otherwise."""
    if request.param is None:
        return
    import functools

    from fuzzkit.codegen import verify
    from fuzzkit.codegen.backends.python import config

    fewer = functools.partial(verify.verify_exact_python, n=request.param)
    monkeypatch.setattr(config, "verify_exact_python", fewer)
    monkeypatch.setattr(
        config, "verify_python", functools.partial(verify.verify_python, n=request.param)
    )
