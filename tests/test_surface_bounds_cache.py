"""The disk cache of the exact surface's sound bounds (``surface_bounds``): a second run reads
back the same arrays instead of paying the branch and bound, and the key separates rule bases
and centres. ``compute`` is replaced by a stub that counts its calls (the bounds themselves are
tested in ``test_stability_sound_bounds.py``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from fuzzkit.analysis import surface_bounds as sb
from fuzzkit.control.loop_rulebase import load_loop_rulebase


def _stub(calls: list[float]) -> object:
    def compute(rb: object, centre: float = 0.0) -> sb.SurfaceBounds:
        calls.append(centre)
        rect = np.array([[-1.0, 0.0, -1.0, 1.0], [0.0, 1.0, -1.0, 1.0]])
        f = np.array([[-0.5, 0.1], [0.0, 0.5]]) + centre
        return sb.SurfaceBounds(rect, f, f * 2.0, f * 3.0, 0.01, 0.002)

    return compute


def test_bounds_are_read_back_from_disk(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("FUZZKIT_CACHE_DIR", str(tmp_path))
    calls: list[float] = []
    monkeypatch.setattr(sb, "compute", _stub(calls))
    rb = load_loop_rulebase("macvicar_whelan")
    sb.surface_bounds.cache_clear()
    first = sb.surface_bounds(rb, 0.25)
    sb.surface_bounds.cache_clear()  # a new process: only the disk is left
    second = sb.surface_bounds(rb, 0.25)
    assert calls == [0.25]
    assert isinstance(first, sb.SurfaceBounds) and isinstance(second, sb.SurfaceBounds)
    for name in ("rect", "f", "dx", "dy"):
        assert np.array_equal(getattr(first, name), getattr(second, name))
    assert (second.tolerance, second.gap) == (0.01, 0.002)
    sb.surface_bounds(rb, 0.5)  # another centre is another entry
    sb.surface_bounds(load_loop_rulebase("gaussian5"), 0.25)  # and another rule base
    assert calls == [0.25, 0.5, 0.25]
    assert len(list(tmp_path.glob("bounds-*.npz"))) == 3
    sb.surface_bounds.cache_clear()


def test_an_unreadable_cache_file_is_computed_again(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("FUZZKIT_CACHE_DIR", str(tmp_path))
    calls: list[float] = []
    monkeypatch.setattr(sb, "compute", _stub(calls))
    rb = load_loop_rulebase("macvicar_whelan")
    sb.surface_bounds.cache_clear()
    sb.surface_bounds(rb, 0.0)
    (path,) = tmp_path.glob("bounds-*.npz")
    path.write_bytes(b"not an npz")
    sb.surface_bounds.cache_clear()
    again = sb.surface_bounds(rb, 0.0)
    assert calls == [0.0, 0.0]
    assert isinstance(again, sb.SurfaceBounds)
    sb.surface_bounds.cache_clear()
