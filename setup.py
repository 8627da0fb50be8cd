"""The package list and package data, derived from the source tree (pyproject.toml holds the rest).

``fuzzkit/`` is the package; ``codegen/``, ``planar_sim/`` and ``rulebases/`` stay top-level
folders in the repository but install as ``fuzzkit.codegen``, ``fuzzkit.planar_sim`` and
``fuzzkit.rulebases`` (:data:`MAPPED_FOLDERS`). Every folder with an ``__init__.py`` under those
is a package of the wheel, and every other file in a package's folder (templates, YAML,
``py.typed``; caches excepted) is its package data, so a new subpackage or data file cannot go
missing from the wheel (``tests/test_packaging.py`` checks the built wheel against the tree).
"""

from __future__ import annotations

from pathlib import Path

from setuptools import find_packages, setup

ROOT = Path(__file__).resolve().parent

#: Repository folders installed inside the ``fuzzkit`` package, under the same name.
MAPPED_FOLDERS = ("codegen", "planar_sim", "rulebases")

_NOT_DATA = (".py", ".pyc", ".pyo")


def package_folders() -> dict[str, Path]:
    """Every installed package name and the repository folder it is built from."""
    out = {
        name: ROOT / name.replace(".", "/")
        for name in find_packages(str(ROOT), include=["fuzzkit*"])
    }
    for folder in MAPPED_FOLDERS:
        for name in find_packages(str(ROOT), include=[folder, f"{folder}.*"]):
            out[f"fuzzkit.{name}"] = ROOT / name.replace(".", "/")
    return out


def package_data(folders: dict[str, Path]) -> dict[str, list[str]]:
    """Per package, the files in its folder that are not Python source (not in a subpackage)."""
    subpackages = set(folders.values())
    data: dict[str, list[str]] = {}
    for name, folder in folders.items():
        files = []
        for path in sorted(folder.rglob("*")):
            if not path.is_file() or path.name.endswith(_NOT_DATA) or "__pycache__" in path.parts:
                continue
            if any(p in subpackages for p in path.parents if p != folder and folder in p.parents):
                continue  # a subpackage's own data
            files.append(path.relative_to(folder).as_posix())
        if files:
            data[name] = files
    return data


if __name__ == "__main__":
    FOLDERS = package_folders()
    setup(
        packages=sorted(FOLDERS),
        package_dir={f"fuzzkit.{folder}": folder for folder in MAPPED_FOLDERS},
        package_data=package_data(FOLDERS),
    )
