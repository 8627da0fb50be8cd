"""A compiled kernel's cache key covers its module's import closure, and nothing more.

The closure rules are checked on small package trees written here (an edit outside the closure
keeps the digest, an edit inside it, at any depth, or a move changes it); then the real package's
kernels are checked to be stamped with their own module's closure.
"""

from __future__ import annotations

from pathlib import Path

import numba
import pytest
from numba.core.registry import CPUDispatcher

from fuzzkit import jit as jit_module
from fuzzkit.import_closure import ImportGraph

#: The package's kernel modules: every module that compiles a function with ``fuzzkit.jit``.
KERNEL_MODULES = (
    "fuzzkit.fuzzy.grid_kernel",
    "fuzzkit.plants.arm6_heightfield",
    "fuzzkit.plants.arm6_period",
    "fuzzkit.plants.rough_profile",
    "fuzzkit.planar_sim.arm_period",
    "fuzzkit.studies.compiled.arm6_run",
    "fuzzkit.studies.compiled.generated_c",
    "fuzzkit.studies.compiled.generated_controller",
    "fuzzkit.studies.compiled.period",
    "fuzzkit.studies.compiled.planar_run",
    "fuzzkit.studies.compiled.table",
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


def test_plain_import_reaches_every_package_on_the_dotted_path(tree: Path) -> None:
    # `import pkg.mapped.util` binds `pkg`: pkg's and pkg.mapped's globals are reachable too
    _write(tree, {"pkg/plain.py": "import pkg.mapped.util\n"})
    assert _graph(tree).closure("pkg.plain") == (
        "pkg",
        "pkg.mapped",
        "pkg.mapped.util",
        "pkg.plain",
    )


def test_a_name_imported_from_a_package_follows_its_init(tree: Path) -> None:
    # pkg.sub's __init__ defines `helper` (from pkg.other); `consts` is a submodule
    _write(tree, {"pkg/names.py": "from pkg.sub import helper, consts\n"})
    closure = _graph(tree).closure("pkg.names")
    assert {"pkg.sub", "pkg.other", "pkg.sub.consts"} <= set(closure)


def test_an_import_under_if_try_or_class_counts(tree: Path) -> None:
    _write(
        tree,
        {
            "pkg/guarded.py": (
                "import sys\n"
                "if sys.platform:\n    from pkg import deep\nelse:\n    pass\n"
                "try:\n    pass\nexcept ImportError:\n    from pkg.sub import consts\n"
                "class Holder:\n    from pkg import lazy\n"
            )
        },
    )
    closure = _graph(tree).closure("pkg.guarded")
    assert {"pkg.deep", "pkg.sub.consts", "pkg.lazy"} <= set(closure)


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
    # a new kernel module must be warmed (fuzzkit.studies.compiled.warm) and is checked below
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
    closure = set(jit_module.package_graph().closure("fuzzkit.studies.compiled.arm6_run"))
    assert {
        "fuzzkit.studies.compiled.arm6_run",
        "fuzzkit.studies.compiled.period",  # faults and latency, called every period
        "fuzzkit.studies.compiled.generated_controller",  # the controller's period
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
    closure = graph.closure("fuzzkit.studies.compiled.planar_run")
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
