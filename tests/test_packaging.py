"""Packaging: one top-level package, the documentation in the sdist, a wheel that runs the demo.

Built from a clean copy of the repository (no build folders, no virtual environments). ``make
test`` builds the sdist and the wheel from it with the environment's own (locked) setuptools
(``--no-isolation``: seconds, no download) and checks their file lists, which is what catches a
missing module, template or data file. ``make verify`` builds them as a user or a release job
does (an isolated build environment, the wheel built from the unpacked sdist, so a file the
sdist lacks cannot reach the wheel either), checks the same lists and installs the wheel
outside the repository to run the demo.
"""

from __future__ import annotations

import pydoc
import shutil
import subprocess
import sys
import tarfile
import zipfile
from collections.abc import Callable
from pathlib import Path

import pytest
from _pairwise import verify

import fuzzkit

ROOT = Path(__file__).resolve().parent.parent

#: What the README's API tour uses from ``import fuzzkit``.
API_TOUR = ("Engine", "available", "dump", "evaluate", "evaluate_point", "load", "loads")


def test_import_fuzzkit_shows_the_api_tour_in_dir_and_help() -> None:
    assert set(API_TOUR) <= set(dir(fuzzkit))
    text = pydoc.render_doc(fuzzkit, renderer=pydoc.plaintext)
    for name in API_TOUR:
        assert name in text
    assert callable(fuzzkit.evaluate_point)
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        _ = fuzzkit.nope  # type: ignore[attr-defined]


def test_python_dash_m_fuzzkit_is_the_fuzzkit_command() -> None:
    run = subprocess.run(
        [sys.executable, "-m", "fuzzkit", "--version"], capture_output=True, text=True, timeout=60
    )
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == f"fuzzkit {fuzzkit.__version__}"


#: The repository folders installed inside ``fuzzkit`` under the same name (issue 19).
MAPPED_FOLDERS = ("codegen", "planar_sim", "rulebases")


def source_files() -> list[str]:
    """Every file of the package's source folders, as its path inside the wheel."""
    out = []
    for top in ("fuzzkit", *MAPPED_FOLDERS):
        for path in sorted((ROOT / top).rglob("*")):
            if path.is_file() and "__pycache__" not in path.parts and path.suffix != ".pyc":
                rel = path.relative_to(ROOT).as_posix()
                out.append(rel if top == "fuzzkit" else f"fuzzkit/{rel}")
    return out


def test_every_top_level_package_folder_is_fuzzkit_or_mapped_into_it() -> None:
    folders = {p.parent.name for p in ROOT.glob("*/__init__.py")}
    assert folders == {"fuzzkit", *MAPPED_FOLDERS}


@pytest.mark.parametrize("folder", MAPPED_FOLDERS)
def test_a_mapped_folder_imported_from_the_repository_root_names_its_package(folder: str) -> None:
    run = subprocess.run(
        [sys.executable, "-c", f"import {folder}"],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=60,
    )
    assert run.returncode == 1
    last = run.stderr.strip().splitlines()[-1]
    assert last.startswith("ImportError:") and f"import fuzzkit.{folder} " in last, run.stderr


def test_make_typecheck_sees_every_mapped_folder(tmp_path: Path) -> None:
    """``make typecheck`` (mypy on the installed layout) reports a type error planted in each
    mapped folder and in a new subpackage of one, and passes on the same tree without them."""
    if shutil.which("make") is None:
        pytest.skip("no make")
    tree = tmp_path / "repo"
    for name in ("Makefile", "pyproject.toml", "setup.py"):
        (tree / name).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(ROOT / name, tree / name)
    for top in ("fuzzkit", *MAPPED_FOLDERS, "codegen/backends/new_target"):
        (tree / top).mkdir(parents=True, exist_ok=True)
        (tree / top / "__init__.py").write_text('"""A package."""\n')
    (tree / ".venv").symlink_to(Path(sys.prefix))
    make = ["make", "-C", str(tree), "-o", ".venv/.fuzzkit-installed", "typecheck"]
    clean = subprocess.run(make, capture_output=True, text=True, timeout=300)
    assert clean.returncode == 0, clean.stdout[-3000:] + clean.stderr[-3000:]
    planted = [*MAPPED_FOLDERS, "codegen/backends/new_target"]
    for top in planted:
        (tree / top / "planted.py").write_text('def f() -> int:\n    return "not an int"\n')
    run = subprocess.run(make, capture_output=True, text=True, timeout=300)
    assert run.returncode != 0
    for top in planted:
        assert f"fuzzkit/{top}/planted.py:2: error: Incompatible return value" in run.stdout, (
            run.stdout[-3000:]
        )


#: The two builds: ``make test``'s quick one, ``make verify``'s release build.
BUILDS = [pytest.param(False, id="cover"), pytest.param(True, marks=verify, id="full")]


@pytest.fixture(scope="module", params=BUILDS)
def dists(
    request: pytest.FixtureRequest, built_dists: Callable[[bool], tuple[Path, Path]]
) -> tuple[Path, Path]:
    """(wheel, sdist) of one of :data:`BUILDS`, built once per run (``tests/conftest.py``)."""
    return built_dists(request.param)


@pytest.mark.slow
def test_wheel_installs_one_top_level_package(dists: tuple[Path, Path]) -> None:
    wheel, _ = dists
    with zipfile.ZipFile(wheel) as zf:
        names = zf.namelist()
    top = {n.split("/", 1)[0] for n in names}
    assert {t for t in top if not t.endswith(".dist-info")} == {"fuzzkit"}
    for expected in (
        "fuzzkit/codegen/emit.py",
        "fuzzkit/codegen/backends/c/source.c.jinja",
        "fuzzkit/planar_sim/arm.py",
        "fuzzkit/rulebases/macvicar_whelan.yaml",
        "fuzzkit/py.typed",
    ):
        assert expected in names
    assert any(n.endswith(".dist-info/licenses/LICENSE") for n in names)
    # every file of the source tree (modules, templates, YAML, markers) is in the wheel, at its
    # installed name: a new subpackage or data file cannot go missing
    missing = sorted(set(source_files()) - set(names))
    assert not missing, missing


@pytest.mark.slow
def test_sdist_carries_license_readme_and_docs(dists: tuple[Path, Path]) -> None:
    _, sdist = dists
    with tarfile.open(sdist) as tf:
        names = {n.split("/", 1)[1] for n in tf.getnames() if "/" in n}
    for expected in ("LICENSE", "README.md", "docs/rulebase-format.md", "pyproject.toml"):
        assert expected in names
    assert any(n.startswith("tests/golden/") for n in names)


@pytest.mark.slow
@pytest.mark.needs_cc
@verify
def test_wheel_runs_the_demo_outside_the_repository(
    built_dists: Callable[[bool], tuple[Path, Path]], tmp_path: Path
) -> None:
    if shutil.which("cc") is None and shutil.which("gcc") is None:
        pytest.skip("no C compiler: the demo compiles the generated C")
    wheel, _ = built_dists(True)
    target = tmp_path / "site"
    pip = subprocess.run(
        [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--target", str(target),
         str(wheel)],
        capture_output=True,
        text=True,
        timeout=300,
    )  # fmt: skip
    assert pip.returncode == 0, pip.stderr[-3000:]
    # -S: site-packages' .pth files (the editable install's finder) cannot shadow the wheel;
    # site-packages itself stays reachable through PYTHONPATH for numpy, pymunk, ...
    site_dirs = [p for p in sys.path if p.endswith("site-packages")]
    env = {"PATH": "/usr/bin:/bin", "PYTHONPATH": ":".join([str(target), *site_dirs])}
    out = tmp_path / "demo"
    run = subprocess.run(
        [sys.executable, "-S", "-m", "fuzzkit", "demo", "--out", str(out)],
        capture_output=True,
        text=True,
        env=env,
        cwd=tmp_path,
        timeout=600,
    )
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    assert str(target) in subprocess.run(
        [sys.executable, "-S", "-c", "import fuzzkit; print(fuzzkit.__file__)"],
        capture_output=True, text=True, env=env, cwd=tmp_path, timeout=60,
    ).stdout  # fmt: skip
    assert (out / "c" / "macvicar_whelan.c").is_file()
    assert (out / "macvicar_whelan_surface.png").stat().st_size > 1000
