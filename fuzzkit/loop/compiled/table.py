"""The generated lookup table's arithmetic in compiled code (double-precision 2-D tables).

The same operations, in the same order, as
``fuzzkit.codegen.lookup_table.LookupTable.interpolate`` for
``number_type="double"`` (bit for bit) and as the generated C: clamp to the breakpoint range,
locate the cell, then linear interpolation on the cell's triangle (the diagonal each cell's
``splits`` names). One difference from the C: it multiplies by a stored reciprocal of the cell
width where this divides, so a value can differ in its last bit (docs/compiled_loop.md).
"""

from __future__ import annotations

import hashlib
import io
import math
import os
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.errors import ConfigError
from fuzzkit.jit import jit

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


@jit
def _locate(bp: FloatArray, x: float) -> tuple[int, float]:
    """Cell index and fraction of ``x`` clamped to ``bp``'s range (``_locate_float``)."""
    n = bp.shape[0]
    xc = min(max(x, bp[0]), bp[n - 1])
    # searchsorted(bp, xc, side="right") - 1, then clipped to [0, n - 2]
    lo, hi = 0, n
    while lo < hi:
        mid = (lo + hi) // 2
        if bp[mid] <= xc:
            lo = mid + 1
        else:
            hi = mid
    i = min(max(lo - 1, 0), n - 2)
    return i, (xc - bp[i]) / (bp[i + 1] - bp[i])


@jit
def table2(
    bp0: FloatArray, bp1: FloatArray, tab: FloatArray, splits: IntArray, x0: float, x1: float
) -> float:
    """Interpolate a 2-D double table at ``(x0, x1)``; NaN in, NaN out."""
    if math.isnan(x0) or math.isnan(x1):
        return math.nan
    i, t0 = _locate(bp0, x0)
    j, t1 = _locate(bp1, x1)
    v00, v10 = tab[i, j], tab[i + 1, j]
    v01, v11 = tab[i, j + 1], tab[i + 1, j + 1]
    if splits[i, j] != 0:
        s0, w00, w10, w01, w11 = 1.0 - t0, v10, v00, v11, v01
    else:
        s0, w00, w10, w01, w11 = t0, v00, v10, v01, v11
    if s0 >= t1:
        vm, hi_, lo_ = w10, s0, t1
    else:
        vm, hi_, lo_ = w01, t1, s0
    return float(w00 + hi_ * (vm - w00) + lo_ * (w11 - vm))


@dataclass(frozen=True, slots=True)
class TableArrays:
    """A 2-input, 1-output double lookup table as the compiled loop reads it, and its name."""

    bp0: FloatArray  # breakpoints of e
    bp1: FloatArray  # breakpoints of de
    values: FloatArray  # (len(bp0), len(bp1))
    splits: IntArray  # (len(bp0) - 1, len(bp1) - 1): 1 where a cell is split on its anti-diagonal
    label: str


def table_arrays(table: Any) -> TableArrays:
    """The :class:`TableArrays` of a ``fuzzkit.codegen.lookup_table.LookupTable`` (double, 2
    inputs).

    Raises
    ------
    ConfigError
        If the table is not a double table with two inputs and one output.
    """
    if isinstance(table, TableArrays):
        return table
    if table.number_type != "double" or len(table.breakpoints) != 2 or len(table.stored) != 1:
        raise ConfigError(
            "the compiled loop runs a double lookup table with inputs (e, de) and one output "
            f"(got {table.number_type}, {len(table.breakpoints)} inputs, "
            f"{len(table.stored)} outputs)"
        )
    tab = np.ascontiguousarray(table.stored[0], dtype=np.float64)
    splits = (
        np.zeros((tab.shape[0] - 1, tab.shape[1] - 1), dtype=np.int64)
        if table.splits is None
        else np.ascontiguousarray(table.splits, dtype=np.int64)
    )
    shape = "x".join(str(s) for s in table.shape)
    return TableArrays(
        bp0=np.ascontiguousarray(table.breakpoints[0], dtype=np.float64),
        bp1=np.ascontiguousarray(table.breakpoints[1], dtype=np.float64),
        values=tab,
        splits=splits,
        label=f"lookup table {table.rule_base_name} {shape} double, bound {table.bound[0]:.2e}",
    )


@lru_cache(maxsize=8)
def load_table(rulebase: str = "macvicar_whelan", tolerance: float = 1e-3) -> Any:
    """The double lookup table of a rule base (shipped name or YAML path), as ``fuzzkit compile
    --target c --type double --tolerance`` builds it: what the compiled fuzzy-PI evaluates and
    the generated C (:mod:`fuzzkit.loop.compiled.generated_c`) is emitted from."""
    from fuzzkit.codegen.table_search import make_table
    from fuzzkit.control.loop_rulebase import load_loop_rulebase

    return make_table(load_loop_rulebase(rulebase), number_type="double", tolerance=tolerance)


def cache_dir() -> Path:
    """Where built tables are kept: ``$FUZZKIT_CACHE_DIR``, else ``~/.cache/fuzzkit/tables``."""
    env = os.environ.get("FUZZKIT_CACHE_DIR")
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "fuzzkit" / "tables"


def cached_table(rb: Any, tolerance: float, build: Callable[[], Any]) -> TableArrays:
    """The table of rule base ``rb`` at ``tolerance``, built by ``build()`` once and kept on disk.

    Building (search plus certification of the bound) costs seconds; a run should not pay it
    every time. The key is the SHA-256 of the rule base model, the tolerance and the fuzzkit
    version, so an edited rule base or a new release builds afresh. An unreadable cache file is
    rebuilt, never trusted.
    """
    from fuzzkit import __version__

    key = hashlib.sha256(f"{rb!r}|{tolerance!r}|{__version__}".encode()).hexdigest()[:32]
    path = cache_dir() / f"{key}.npz"
    try:
        with np.load(path, allow_pickle=False) as z:
            return TableArrays(
                bp0=z["bp0"],
                bp1=z["bp1"],
                values=z["values"],
                splits=z["splits"],
                label=str(z["label"]),
            )
    except (OSError, KeyError, ValueError):
        pass
    arrays = table_arrays(build())
    store_npz(
        path,
        bp0=arrays.bp0,
        bp1=arrays.bp1,
        values=arrays.values,
        splits=arrays.splits,
        label=np.array(arrays.label),
    )
    return arrays


def store_npz(path: Path, **arrays: npt.ArrayLike) -> None:
    """Keep ``arrays`` in the cache file ``path`` (written whole or not at all); a read-only
    cache only costs the computation next time."""
    from fuzzkit.fileio import write_atomic

    buf = io.BytesIO()
    np.savez(buf, **arrays)  # type: ignore[arg-type]
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        write_atomic(path, buf.getvalue())
    except OSError:
        pass


def compiled_table(rulebase: str = "macvicar_whelan", tolerance: float = 1e-3) -> TableArrays:
    """:func:`load_table`'s arrays, from the on-disk cache after the first build."""
    from fuzzkit.control.loop_rulebase import load_loop_rulebase

    return cached_table(
        load_loop_rulebase(rulebase), tolerance, lambda: load_table(rulebase, tolerance)
    )
