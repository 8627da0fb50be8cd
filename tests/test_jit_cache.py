"""fuzzkit's compiled kernels are cached against the whole package, not only their own file."""

from __future__ import annotations

from pathlib import Path

from fuzzkit import jit as jit_module
from fuzzkit.studies.compiled import arm6_run, period


def _tree(root: Path, files: dict[str, str]) -> Path:
    for rel, text in files.items():
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        (root / rel).write_text(text)
    return root


def test_fingerprint_changes_with_any_source_file(tmp_path: Path) -> None:
    root = _tree(tmp_path / "pkg", {"a.py": "x = 1\n", "sub/b.py": "y = 2\n", "c.txt": "z"})
    before = jit_module.fingerprint_of([root])
    assert jit_module.fingerprint_of([root]) == before  # deterministic
    (root / "c.txt").write_text("not python")  # only sources count
    assert jit_module.fingerprint_of([root]) == before
    (root / "sub" / "b.py").write_text("y = 3\n")  # a callee's edit
    assert jit_module.fingerprint_of([root]) != before
    (root / "sub" / "b.py").write_text("y = 2\n")
    assert jit_module.fingerprint_of([root]) == before
    (root / "sub" / "b.py").rename(root / "b.py")  # a move is a change
    assert jit_module.fingerprint_of([root]) != before


def test_the_roots_cover_every_mapped_folder() -> None:
    names = {p.name for p in jit_module.package_roots()}
    assert {"fuzzkit", "codegen", "planar_sim"} <= names


def test_a_kernel_is_stamped_with_the_package_fingerprint() -> None:
    # the run loop calls period.py's functions: its cache must depend on more than arm6_run.py
    for dispatcher in (arm6_run.run_arm6, period.inject_faults):
        locator = dispatcher._cache._impl.locator
        assert isinstance(locator, jit_module._PackageStamp), type(locator)
        own, package = locator.get_source_stamp()
        assert package == jit_module.source_fingerprint()
        assert own  # numba's own stamp of the kernel's file is kept as well


def test_code_outside_the_package_keeps_numba_locators() -> None:
    import numba

    def outside(x: float) -> float:
        return x + 1.0

    outside.__module__ = "elsewhere"
    dispatcher = numba.njit(cache=True)(outside)
    # this test file is not a fuzzkit source: numba's own locator serves it
    locator = dispatcher._cache._impl.locator
    assert not isinstance(locator, jit_module._PackageStamp)
