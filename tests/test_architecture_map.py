"""docs/architecture.md's map names every module under ``fuzzkit/`` (issue 37, item 5).

A module is named when a row of the map's tables names its package (``fuzzkit/loop/``) and,
in that row, the module's path below it (``run.py``; ``compiled/skeleton.py`` or ``compiled/``
with ``skeleton.py``); a module directly under ``fuzzkit/`` (and a ``__main__.py``) by its
whole path. Package ``__init__.py`` files say what their package holds themselves.
"""

from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
MAP = ROOT / "docs" / "architecture.md"


def map_rows(text: str) -> list[str]:
    """The rows of the map's tables."""
    return [line for line in text.splitlines() if line.startswith("| ")]


def modules() -> list[str]:
    """Every module under ``fuzzkit/`` but the packages' ``__init__.py``, as a path."""
    found = (p for p in (ROOT / "fuzzkit").rglob("*.py") if "__pycache__" not in p.parts)
    return sorted(p.relative_to(ROOT).as_posix() for p in found if p.name != "__init__.py")


def named(module: str, rows: list[str]) -> bool:
    """Whether a row of ``rows`` names ``module`` (a path such as ``fuzzkit/loop/run.py``)."""
    parts = module.split("/")
    if len(parts) == 2 or parts[-1] == "__main__.py":
        return any(f"`{module}`" in row for row in rows)
    for i in range(2, len(parts)):
        package, rest = "/".join(parts[:i]) + "/", parts[i:]
        for row in rows:
            if f"`{package}`" not in row:
                continue
            if f"`{'/'.join(rest)}`" in row:
                return True
            folders = [f"`{'/'.join(rest[:j])}/`" for j in range(1, len(rest))]
            if all(f in row for f in folders) and f"`{rest[-1]}`" in row:
                return True
    return False


def test_the_map_names_every_module() -> None:
    rows = map_rows(MAP.read_text(encoding="utf-8"))
    found = modules()
    assert len(found) > 150  # the walk found the package
    missing = [m for m in found if not named(m, rows)]
    assert not missing, f"docs/architecture.md's map does not name: {missing}"


@pytest.mark.parametrize(
    ("module", "row", "expected"),
    [
        ("fuzzkit/loop/run.py", "| `fuzzkit/loop/` | `run.py` (the entry) |", True),
        ("fuzzkit/loop/compiled/period.py", "| `fuzzkit/loop/` | `compiled/`: `period.py` |", True),
        ("fuzzkit/loop/compiled/period.py", "| `fuzzkit/loop/` | `period.py` |", False),
        ("fuzzkit/loop/run.py", "| `fuzzkit/studies/` | `run.py` |", False),
        ("fuzzkit/errors.py", "| `fuzzkit/errors.py` | exceptions |", True),
        ("fuzzkit/errors.py", "| `fuzzkit/` | `errors.py` |", False),
    ],
)  # fmt: skip
def test_a_module_is_named_in_its_own_package_row(module: str, row: str, expected: bool) -> None:
    # the check can fail: a name in another package's row, or without its folder, is no name
    assert named(module, [row]) is expected
