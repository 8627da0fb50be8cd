"""The package list and package data, derived from the source tree (pyproject.toml holds the rest).

``fuzzkit/`` is the package; ``codegen/``, ``planar_sim/`` and ``rulebases/`` stay top-level
folders in the repository but install as ``fuzzkit.codegen``, ``fuzzkit.planar_sim`` and
``fuzzkit.rulebases`` (:data:`MAPPED_FOLDERS`). Every folder under those is a package of the
wheel (a folder without an ``__init__.py``, such as ``fuzzkit/data``, a namespace package), and
every other file in a package's folder (templates, YAML, ``py.typed``; caches excepted) is its
package data, so a new subpackage or data file cannot go missing from the wheel
(``tests/test_packaging.py`` checks the built wheel against the tree).
"""

from __future__ import annotations

from pathlib import Path

from setuptools import find_namespace_packages, setup

ROOT = Path(__file__).resolve().parent

#: Repository folders installed inside the ``fuzzkit`` package, under the same name.
MAPPED_FOLDERS = ("codegen", "planar_sim", "rulebases")

_NOT_DATA = (".py", ".pyc", ".pyo")
_SKIP = ["*__pycache__*"]


def package_folders() -> dict[str, Path]:
    """Every installed package name and the repository folder it is built from."""
    out = {}
    for top in ("fuzzkit", *MAPPED_FOLDERS):
        for name in find_namespace_packages(str(ROOT), include=[top, f"{top}.*"], exclude=_SKIP):
            installed = name if top == "fuzzkit" else f"fuzzkit.{name}"
            out[installed] = ROOT / name.replace(".", "/")
    return out


def package_data(folders: dict[str, Path]) -> dict[str, list[str]]:
    """Per package, the files directly in its folder that are not Python source."""
    data: dict[str, list[str]] = {}
    for name, folder in folders.items():
        files = sorted(
            p.name for p in folder.iterdir() if p.is_file() and not p.name.endswith(_NOT_DATA)
        )
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
