"""A compiled kernel's cache key covers its module's import closure, and nothing more; the
kernels are warmed before the test workers start.

The closure rules are checked on small package trees written here (an edit outside the closure
keeps the digest, an edit inside it, at any depth, or a move changes it); then the real package's
kernels are checked to be stamped with their own module's closure. Compiling every kernel from
an empty cache takes about a minute of CPU, so no test here does it end to end:
``python -m fuzzkit.studies.warm`` with an empty ``NUMBA_CACHE_DIR`` does, by hand.
"""

from __future__ import annotations

import importlib
import json
import os
import sys
import threading
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numba
import pytest
from numba.core.registry import CPUDispatcher

from fuzzkit import jit as jit_module
from fuzzkit.errors import ToolchainError
from fuzzkit.import_closure import ImportGraph
from fuzzkit.studies import warm as warm_module

#: The package's kernel modules: every module that compiles a function with ``fuzzkit.jit``.
KERNEL_MODULES = (
    "fuzzkit.fuzzy.grid_kernel",
    "fuzzkit.fuzzy.type2_kernel",
    "fuzzkit.fuzzy.type_reduction",
    "fuzzkit.plants.arm6_heightfield",
    "fuzzkit.plants.arm6_period",
    "fuzzkit.plants.rough_profile",
    "fuzzkit.planar_sim.arm_period",
    "fuzzkit.loop.compiled.arm6_run",
    "fuzzkit.loop.compiled.generated_controller",
    "fuzzkit.loop.compiled.mujoco_run",
    "fuzzkit.loop.compiled.period",
    "fuzzkit.loop.compiled.planar_run",
    "fuzzkit.loop.compiled.skeleton",
    "fuzzkit.loop.compiled.table",
)

#: A package ``pkg`` (with ``pkg.mapped`` in a folder of its own, as fuzzkit.codegen is):
#: ``kern`` holds the kernel; it calls ``callee``, which calls ``deep``; it reads a constant of
#: ``consts``; ``other`` imports ``kern`` (the wrong way round: not in kern's closure), and
#: ``lazy`` is imported inside a Python function only.
TREE = {
    "pkg/__init__.py": "",
    "pkg/sub/__init__.py": "from pkg.other import helper\n",
    "pkg/sub/kern.py": (
        "from pkg.sub.callee import step\n"
        "from . import consts\n"
        "import pkg.mapped.util as util\n"
        "def python_only():\n"
        "    from pkg import lazy\n"
        "    return lazy\n"
    ),
    "pkg/sub/callee.py": "from ..deep import inner\ndef step(x):\n    return inner(x)\n",
    "pkg/sub/consts.py": "GAIN = 2.0\n",
    "pkg/deep.py": "def inner(x):\n    return x\n",
    "pkg/other.py": "from pkg.sub import kern\ndef helper():\n    return kern\n",
    "pkg/lazy.py": "VALUE = 1\n",
    "mapped/__init__.py": "",
    "mapped/util.py": "SCALE = 3\n",
    "mapped/unused.py": "",
}


def _write(root: Path, files: dict[str, str]) -> None:
    for rel, text in files.items():
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        (root / rel).write_text(text)


def _graph(root: Path) -> ImportGraph:
    return ImportGraph({"pkg": root / "pkg", "pkg.mapped": root / "mapped"})


@pytest.fixture
def tree(tmp_path: Path) -> Path:
    _write(tmp_path, TREE)
    return tmp_path


def test_the_closure_follows_module_scope_imports_only(tree: Path) -> None:
    assert _graph(tree).closure("pkg.sub.kern") == (
        "pkg.deep",
        "pkg.mapped.util",
        "pkg.sub.callee",
        "pkg.sub.consts",
        "pkg.sub.kern",
    )


@pytest.mark.parametrize(
    "statement, reached",
    [
        # `import pkg.mapped.util` binds `pkg`: pkg's and pkg.mapped's globals are reachable
        ("import pkg.mapped.util", {"pkg", "pkg.mapped", "pkg.mapped.util"}),
        # pkg.sub's __init__ defines `helper` (from pkg.other); `consts` is a submodule
        ("from pkg.sub import helper, consts", {"pkg.sub", "pkg.other", "pkg.sub.consts"}),
    ],
)
def test_what_an_import_statement_binds_is_followed(
    tree: Path, statement: str, reached: set[str]
) -> None:
    _write(tree, {"pkg/importer.py": statement + "\n"})
    closure = set(_graph(tree).closure("pkg.importer")) - {"pkg.importer"}
    # what those modules import comes too; the top package only where the statement binds it
    assert reached <= closure
    assert ("pkg" in closure) == ("pkg" in reached)


def test_an_import_under_if_try_or_class_counts(tree: Path) -> None:
    _write(
        tree,
        {
            "pkg/guarded.py": (
                "import sys\n"
                "if sys.platform == 'never':\n    pass\nelse:\n    from pkg import deep\n"
                "try:\n    pass\nexcept ImportError:\n    from pkg.sub import consts\n"
                "finally:\n    from pkg.mapped import util\n"
                "class Holder:\n    from pkg import lazy\n"
            )
        },
    )
    closure = _graph(tree).closure("pkg.guarded")
    assert {"pkg.deep", "pkg.sub.consts", "pkg.mapped.util", "pkg.lazy"} <= set(closure)


@pytest.mark.parametrize(
    "rel, text",
    [
        ("pkg/other.py", "from pkg.sub import kern\ndef helper():\n    return kern  # edited\n"),
        ("pkg/lazy.py", "VALUE = 2\n"),  # imported only inside a function
        ("pkg/sub/__init__.py", "X = 1\n"),  # an ancestor package of what kern imports from
        ("mapped/unused.py", "Y = 1\n"),
        ("pkg/notes.txt", "not a source file"),
    ],
)
def test_an_edit_outside_the_closure_keeps_the_digest(tree: Path, rel: str, text: str) -> None:
    before = _graph(tree).digest("pkg.sub.kern")
    _write(tree, {rel: text})
    assert _graph(tree).digest("pkg.sub.kern") == before


@pytest.mark.parametrize(
    "rel, text",
    [
        ("pkg/sub/kern.py", TREE["pkg/sub/kern.py"] + "# edited\n"),  # the kernel's own file
        ("pkg/sub/callee.py", "from ..deep import inner\ndef step(x):\n    return -inner(x)\n"),
        ("pkg/deep.py", "def inner(x):\n    return 2 * x\n"),  # two levels down
        ("pkg/sub/consts.py", "GAIN = 2.5\n"),  # a constant the kernel reads
        ("mapped/util.py", "SCALE = 4\n"),  # in a mapped package's folder
    ],
)
def test_an_edit_inside_the_closure_changes_the_digest(tree: Path, rel: str, text: str) -> None:
    before = _graph(tree).digest("pkg.sub.kern")
    _write(tree, {rel: text})
    assert _graph(tree).digest("pkg.sub.kern") != before


def test_a_move_changes_the_digest_even_with_the_same_text(tree: Path) -> None:
    before = _graph(tree).digest("pkg.sub.kern")
    # deep.py is renamed, its text unchanged; its importer follows
    (tree / "pkg" / "deep.py").rename(tree / "pkg" / "moved.py")
    callee = TREE["pkg/sub/callee.py"].replace("..deep", "..moved")
    _write(tree, {"pkg/sub/callee.py": callee})
    moved = _graph(tree)
    assert "pkg.moved" in moved.closure("pkg.sub.kern")
    assert moved.digest("pkg.sub.kern") != before
    # and the same texts under the old names give the old digest back
    (tree / "pkg" / "moved.py").rename(tree / "pkg" / "deep.py")
    _write(tree, {"pkg/sub/callee.py": TREE["pkg/sub/callee.py"]})
    assert _graph(tree).digest("pkg.sub.kern") == before


def test_a_kept_parse_is_used_while_its_source_is_unchanged(tree: Path) -> None:
    def graph() -> ImportGraph:
        return ImportGraph({"pkg": tree / "pkg", "pkg.mapped": tree / "mapped"}, keep=True)

    expected = _graph(tree).closure("pkg.sub.kern")
    assert graph().closure("pkg.sub.kern") == expected
    kept = tree / "pkg" / "sub" / "__pycache__" / "callee.imports.json"
    data = json.loads(kept.read_text())
    # what the next graph finds comes from the kept parse: make it say `from pkg import lazy`
    data["statements"] = [[True, 0, "pkg", ["lazy"], [False]]]
    kept.write_text(json.dumps(data))
    assert "pkg.lazy" in graph().closure("pkg.sub.kern")
    # once the source changes, the kept parse is stale: the source is parsed again
    _write(tree, {"pkg/sub/callee.py": TREE["pkg/sub/callee.py"] + "# edited\n"})
    assert graph().closure("pkg.sub.kern") == expected
    kept.write_text("{not json")  # and an unreadable one is parsed over
    assert graph().closure("pkg.sub.kern") == expected
    assert json.loads(kept.read_text())["statements"]


def test_modules_map_to_their_files_and_back(tree: Path) -> None:
    graph = _graph(tree)
    assert graph.path_of("pkg.mapped.util") == (tree / "mapped" / "util.py").resolve()
    assert graph.path_of("pkg.sub") == (tree / "pkg" / "sub" / "__init__.py").resolve()
    assert graph.path_of("pkg.missing") is None
    assert graph.path_of("elsewhere.util") is None
    assert graph.module_of(tree / "mapped" / "util.py") == "pkg.mapped.util"
    assert graph.module_of(tree / "pkg" / "sub" / "__init__.py") == "pkg.sub"
    assert graph.module_of(tree / "outside.py") is None


# The real package.


def _kernels(module_name: str) -> list[CPUDispatcher]:
    module = __import__(module_name, fromlist=["_"])
    return [
        value
        for value in vars(module).values()
        if isinstance(value, CPUDispatcher) and value.py_func.__module__ == module_name
    ]


def test_every_kernel_module_of_the_package_is_listed() -> None:
    # a new kernel module must be warmed (fuzzkit.studies.warm) and is checked below
    graph = jit_module.package_graph()
    found = set()
    for root in jit_module.package_roots().values():
        for path in root.rglob("*.py"):
            if "from fuzzkit.jit import jit" in path.read_text(encoding="utf-8"):
                found.add(graph.module_of(path))
    assert found == set(KERNEL_MODULES)


@pytest.mark.parametrize("module_name", KERNEL_MODULES)
def test_a_real_kernel_is_stamped_with_its_modules_closure(module_name: str) -> None:
    kernels = _kernels(module_name)
    assert kernels, f"{module_name} defines no kernel"
    digest = jit_module.package_graph().digest(module_name)
    for dispatcher in kernels:
        locator = dispatcher._cache._impl.locator
        assert isinstance(locator, jit_module._ClosureStamp), type(locator)
        assert locator.get_source_stamp() == digest
        # what numba writes into and compares with the index file
        assert dispatcher._cache._cache_file._source_stamp == digest


def test_the_run_loops_closure_holds_its_callees_and_not_the_cli() -> None:
    closure = set(jit_module.package_graph().closure("fuzzkit.loop.compiled.arm6_run"))
    assert {
        "fuzzkit.loop.compiled.arm6_run",
        "fuzzkit.loop.compiled.skeleton",  # the per-period skeleton every loop shares
        "fuzzkit.loop.compiled.period",  # faults and latency, called every period
        "fuzzkit.loop.compiled.generated_controller",  # the controller's period
        "fuzzkit.plants.arm6_period",  # the plant's period
        "fuzzkit.plants.rough_profile",  # two levels down: arm6_period's floor
        "fuzzkit.control.status",  # constants: the status bits
        "fuzzkit.jit",  # how the kernels are compiled
    } <= closure
    # the layers above studies, and the file formats: no kernel reaches them
    outside = {"cli", "viz", "report", "analysis", "formats", "ros2"}
    assert not [m for m in closure if m.split(".")[1] in outside]


def test_the_planar_loops_closure_reaches_the_mapped_planar_package() -> None:
    graph = jit_module.package_graph()
    closure = graph.closure("fuzzkit.loop.compiled.planar_run")
    assert "fuzzkit.planar_sim.arm_period" in closure
    assert "fuzzkit.planar_sim.chipmunk_calls" in closure  # the intrinsics it calls
    from fuzzkit.planar_sim import arm_period

    assert graph.path_of("fuzzkit.planar_sim.arm_period") == Path(arm_period.__file__).resolve()


def test_code_outside_the_package_keeps_numba_locators() -> None:
    def outside(x: float) -> float:
        return x + 1.0

    dispatcher = numba.njit(cache=True)(outside)
    # this test file is not a fuzzkit source: numba's own locator serves it
    locator = dispatcher._cache._impl.locator
    assert not isinstance(locator, jit_module._ClosureStamp)


# Warming.


def test_every_kernel_module_is_reached_by_a_warming_step() -> None:
    graph = jit_module.package_graph()
    reached: set[str] = set()
    for step in warm_module.STEPS:
        for kernel in step.dispatchers():
            reached.update(graph.closure(kernel.py_func.__module__))
    assert set(KERNEL_MODULES) <= reached


def test_has_cached_code_sees_the_disk_cache(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    source = tmp_path / "tiny_kernel.py"
    source.write_text("import numba\n@numba.njit(cache=True)\ndef twice(x):\n    return 2.0 * x\n")
    monkeypatch.syspath_prepend(str(tmp_path))

    def fresh() -> Any:
        sys.modules.pop("tiny_kernel", None)
        return importlib.import_module("tiny_kernel").twice

    kernel = fresh()
    assert not jit_module.has_cached_code(kernel)
    assert kernel(1.5) == 3.0  # compiles and saves
    assert jit_module.has_cached_code(fresh())  # another import of it would load
    source.write_text(source.read_text().replace("2.0 *", "3.0 *"))  # the source changed
    assert not jit_module.has_cached_code(fresh())


def _steps(log: list[str], fail: dict[str, Exception]) -> tuple[Any, ...]:
    """Three warming steps, ``a``, ``b``, ``c``, whose kernel is their name; each logs its run."""

    def step(name: str) -> Any:
        def run() -> None:
            log.append(name)
            if name in fail:
                raise fail[name]

        return warm_module.Step(name, (f"{name}:kernel",), run)

    return tuple(step(name) for name in ("a", "b", "c"))


def test_warm_runs_only_what_is_not_cached_and_reports_why(monkeypatch: pytest.MonkeyPatch) -> None:
    log: list[str] = []
    steps = _steps(log, {"c": ToolchainError("no C compiler found")})
    monkeypatch.setattr(warm_module, "STEPS", steps)
    monkeypatch.setattr(warm_module.Step, "dispatchers", lambda step: [step.name])
    monkeypatch.setattr(warm_module, "has_cached_code", lambda kernel: kernel == "b")
    outcomes: dict[str, str] = {}
    warm_module.warm(lambda name, outcome, seconds: outcomes.__setitem__(name, outcome))
    assert log == ["a", "c"]  # b's kernel was in the cache: not run
    assert outcomes == {"a": "compiled", "b": "cached", "c": "not here: no C compiler found"}


@pytest.mark.parametrize("part, runs", [((0, 2), ["a", "c"]), ((1, 2), ["b"]), ((2, 3), ["c"])])
def test_the_parts_of_a_warm_up_share_the_steps(
    monkeypatch: pytest.MonkeyPatch, part: tuple[int, int], runs: list[str]
) -> None:
    log: list[str] = []
    monkeypatch.setattr(warm_module, "STEPS", _steps(log, {}))
    monkeypatch.setattr(warm_module.Step, "dispatchers", lambda step: [step.name])
    monkeypatch.setattr(warm_module, "has_cached_code", lambda kernel: False)
    warm_module.warm(part=part)
    assert log == runs


def test_warm_lets_a_real_failure_through(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(warm_module, "STEPS", _steps([], {"b": ValueError("broken")}))
    monkeypatch.setattr(warm_module.Step, "dispatchers", lambda step: [step.name])
    monkeypatch.setattr(warm_module, "has_cached_code", lambda kernel: False)
    with pytest.raises(ValueError, match="broken"):
        warm_module.warm()


def _conftest(config: pytest.Config) -> Any:
    for plugin in config.pluginmanager.get_plugins():
        if Path(getattr(plugin, "__file__", "")) == Path(__file__).with_name("conftest.py"):
            return plugin
    raise LookupError("tests/conftest.py is not loaded")


@pytest.mark.parametrize(
    "numprocesses, worker, collect_only, warms",
    [
        (2, False, False, True),  # the controller of `-n 2`: in the background, 2 processes
        (3, False, False, True),
        (2, True, False, False),  # a worker: the controller warms
        (1, False, False, False),  # one worker compiles once anyway
        (0, False, False, False),  # `-n 0`
        (None, False, False, False),  # no -n at all (or xdist not loaded)
        (2, False, True, False),  # --collect-only runs nothing
    ],
)
def test_the_session_hook_warms_only_the_controller_of_several_workers(
    pytestconfig: pytest.Config,
    monkeypatch: pytest.MonkeyPatch,
    numprocesses: int | None,
    worker: bool,
    collect_only: bool,
    warms: bool,
) -> None:
    calls: list[int] = []
    started = object()

    def background(jobs: int) -> object:
        calls.append(jobs)
        return started

    monkeypatch.setattr(warm_module, "warm_in_background", background)
    monkeypatch.setattr(warm_module, "warm", lambda: pytest.fail("warmed in the foreground"))
    config: Any = SimpleNamespace(
        option=SimpleNamespace(numprocesses=numprocesses, collectonly=collect_only),
        stash=pytest.Stash(),
    )
    if worker:
        config.workerinput = {"workerid": "gw0"}
    hooks = _conftest(pytestconfig)
    hooks.pytest_sessionstart(SimpleNamespace(config=config))
    assert calls == ([numprocesses] if warms else [])
    assert (config.stash.get(hooks._WARMING, None) is started) == warms


def _reporting_config(lines: list[str]) -> Any:
    reporter = SimpleNamespace(write_line=lines.append)
    return SimpleNamespace(
        option=SimpleNamespace(numprocesses=2, collectonly=False),
        pluginmanager=SimpleNamespace(get_plugin=lambda name: reporter),
        stash=pytest.Stash(),
    )


def test_a_failing_warm_up_is_reported_at_the_end_and_the_session_goes_on(
    pytestconfig: pytest.Config, monkeypatch: pytest.MonkeyPatch
) -> None:
    hooks = _conftest(pytestconfig)
    lines: list[str] = []
    config = _reporting_config(lines)
    failed = SimpleNamespace(finish=lambda: "exit 1: ValueError: a kernel does not type")
    monkeypatch.setattr(warm_module, "warm_in_background", lambda jobs: failed)
    hooks.pytest_sessionstart(SimpleNamespace(config=config))
    assert lines == []  # the session goes on
    hooks.pytest_sessionfinish(SimpleNamespace(config=config))
    assert lines == ["kernel warm-up failed (exit 1: ValueError: a kernel does not type)"]


def test_without_flock_the_controller_warms_in_the_foreground_and_reports_a_failure(
    pytestconfig: pytest.Config, monkeypatch: pytest.MonkeyPatch
) -> None:
    def broken() -> None:
        raise ValueError("a kernel does not type")

    lines: list[str] = []
    config = _reporting_config(lines)
    monkeypatch.setattr(warm_module, "warm_in_background", lambda jobs: None)
    monkeypatch.setattr(warm_module, "warm", broken)
    _conftest(pytestconfig).pytest_sessionstart(SimpleNamespace(config=config))
    assert lines == ["kernel warm-up failed (ValueError: a kernel does not type)"]


def _waiter() -> tuple[threading.Thread, threading.Event]:
    done = threading.Event()

    def wait() -> None:
        warm_module.wait_for_warming()
        done.set()

    return threading.Thread(target=wait, daemon=True), done


def test_a_worker_waits_while_the_warm_up_holds_its_lock(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import fcntl

    lock = tmp_path / "warm.lock"
    lock.write_text("")
    monkeypatch.setenv(warm_module.LOCK_ENV, str(lock))
    with lock.open() as held:
        fcntl.flock(held, fcntl.LOCK_EX)
        thread, done = _waiter()
        thread.start()
        assert not done.wait(0.5)  # blocked while the lock is held
    assert done.wait(10)  # released: the worker goes on
    lock.unlink()
    thread, done = _waiter()
    thread.start()
    assert done.wait(10)  # a lock file already cleaned up: nothing to wait for
    monkeypatch.delenv(warm_module.LOCK_ENV)
    warm_module.wait_for_warming()  # no warm-up at all


def test_the_background_processes_hold_the_lock_until_the_last_one_exits(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # stand-ins for the warming processes: part k sleeps k/2 s, then says it finished
    def command(part: int, jobs: int) -> list[str]:
        flag = tmp_path / f"part{part}of{jobs}"
        script = (
            f"import pathlib, time; time.sleep({part} / 2); pathlib.Path({str(flag)!r}).touch()"
        )
        return [sys.executable, "-c", script]

    monkeypatch.delenv(warm_module.LOCK_ENV, raising=False)
    warming = warm_module.warm_in_background(2, command)
    assert warming is not None
    try:
        import os

        assert os.environ[warm_module.LOCK_ENV] == str(warming.lock)  # what workers inherit
        warm_module.wait_for_warming()
        assert (tmp_path / "part0of2").exists() and (tmp_path / "part1of2").exists()
    finally:
        assert warming.finish() is None
        monkeypatch.delenv(warm_module.LOCK_ENV)
    assert not warming.lock.exists() and not warming.log.exists()


def test_a_background_process_that_fails_is_reported_with_its_output(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    def command(part: int, jobs: int) -> list[str]:
        if part == 1:
            return [sys.executable, "-c", "raise SystemExit('part 1 broke')"]
        return [sys.executable, "-c", "pass"]

    monkeypatch.delenv(warm_module.LOCK_ENV, raising=False)
    warming = warm_module.warm_in_background(2, command)
    assert warming is not None
    why = warming.finish()
    monkeypatch.delenv(warm_module.LOCK_ENV)
    assert why is not None and why.startswith("exit 1: ") and "part 1 broke" in why


@pytest.mark.parametrize("text", ["1/1", "x/2", "2", "-1/2"])
def test_a_bad_part_is_refused(text: str) -> None:
    with pytest.raises(SystemExit) as exc:
        warm_module.main(["--part", text])
    assert exc.value.code == 2


def test_a_warm_up_waits_for_one_started_before_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # `make test` starts a warm-up (`--background LOCK`) before its static checks and passes
    # LOCK to pytest, whose controller starts its own: that one's processes compile nothing
    # until the first has ended (then they find its kernels cached)
    flag = tmp_path / "finished"

    def command(part: int, jobs: int) -> list[str]:
        script = f"import pathlib, time; time.sleep(1); pathlib.Path({str(flag)!r}).touch()"
        return [sys.executable, "-c", script]

    lock = tmp_path / "build" / "warm.lock"
    monkeypatch.delenv(warm_module.LOCK_ENV, raising=False)
    before = warm_module.warm_in_background(1, command, lock=lock)
    assert before is not None and before.lock == lock and lock.exists()
    assert os.environ[warm_module.LOCK_ENV] == str(lock)
    seen: list[bool] = []
    monkeypatch.setattr(warm_module, "warm", lambda *args: seen.append(flag.exists()))
    try:
        assert warm_module.main(["--part", "0/2"]) == 0
    finally:
        assert before.finish() is None
    assert seen == [True]


def test_the_background_option_starts_the_warm_up_and_returns(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    calls: list[tuple[int, Path | None]] = []

    def background(jobs: int, lock: Path | None = None) -> None:
        calls.append((jobs, lock))

    monkeypatch.setattr(warm_module, "warm_in_background", background)
    monkeypatch.setattr(warm_module, "warm", lambda *a: pytest.fail("warmed in the foreground"))
    lock = tmp_path / "warm.lock"
    assert warm_module.main(["--background", str(lock), "--jobs", "3"]) == 0
    assert calls == [(3, lock)]


@pytest.mark.parametrize("text", ["0", "x", "65"])
def test_a_bad_number_of_jobs_is_refused(text: str) -> None:
    with pytest.raises(SystemExit) as exc:
        warm_module.main(["--background", "warm.lock", "--jobs", text])
    assert exc.value.code == 2
