"""The fuzzy-PI surface the certificate bounds: the one the spec names, in role order.

A controller spec says how its surface is evaluated (``surface:``, :class:`Surface`):

* ``table`` (with a tolerance or a resolution): the deployed surface *is* that lookup table, a
  continuous piecewise-linear function on triangles. Its bounds
  (:mod:`fuzzkit.analysis.fuzzy_bounds`) are exact on it: the certificate covers what runs.
* ``exact`` (the default): the deployed surface is the exact inference. The bounds are exact on
  a table of :data:`PROXY_RESOLUTION` breakpoints per input (a fixed size: no tolerance search,
  so no rule base can fail it) whose values are the exact surface at its nodes;
  ``error_bound`` is that table's certified distance to the exact surface
  (``fuzzkit.codegen``'s bound, measured on a denser check grid). The certificate does **not**
  cover that difference; the output says so, and ``surface: table`` gives a certificate of the
  deployed surface itself.

The loop's rest point (:mod:`fuzzkit.analysis.equilibrium`) is found on the deployed surface
itself in both cases (:meth:`SurfaceSource.on_error_axis`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np
import numpy.typing as npt

from fuzzkit.control.spec import EXACT, Surface
from fuzzkit.fuzzy.model import RuleBase
from fuzzkit.loop.compiled.table import TableArrays, table_arrays

FloatArray = npt.NDArray[np.float64]

#: Breakpoints per input of the table an exact surface is bounded on.
PROXY_RESOLUTION = 129


@dataclass(frozen=True, slots=True)
class SurfaceSource:
    """The table the bounds are exact on, and how it relates to the deployed surface.

    ``covers_deployed``: the table is the deployed surface (``surface: table``).
    ``error_bound``: the certified largest ``|deployed - table|`` (output units; 0 when it is
    the deployed surface). ``rulebase``: the rule base in role order (error, change).
    """

    table: TableArrays
    method: str
    covers_deployed: bool
    error_bound: float
    rulebase: RuleBase

    def on_error_axis(self, xs: FloatArray) -> FloatArray:
        """The deployed surface at ``(x, 0)`` for each ``x`` (scaled error, change 0)."""
        if self.covers_deployed:
            from fuzzkit.loop.compiled.table import table2

            t = self.table
            return np.array([table2(t.bp0, t.bp1, t.values, t.splits, float(x), 0.0) for x in xs])
        from fuzzkit.fuzzy.inference import evaluate

        rb = self.rulebase
        out = evaluate(rb, {rb.inputs[0].name: xs, rb.inputs[1].name: np.zeros_like(xs)})
        return np.asarray(out[rb.outputs[0].name], dtype=np.float64)

    def describe(self) -> str:
        """One line for the output: what the bounds are exact on."""
        if self.covers_deployed:
            return f"exact on the deployed table ({self.table.label})"
        return (
            f"exact on a {PROXY_RESOLUTION}-point table of the exact surface, which differs "
            f"from it by at most {self.error_bound:.3g} (certified on a denser grid): that "
            "difference is not covered (surface: table certifies the deployed surface itself)"
        )


@lru_cache(maxsize=16)
def surface_source(rb: RuleBase, surface: Surface = EXACT) -> SurfaceSource:
    """The :class:`SurfaceSource` of ``rb`` (inputs in role order: error, change; see
    :func:`fuzzkit.control.spec.role_ordered`) evaluated as ``surface``."""
    from fuzzkit.codegen.table_search import make_table
    from fuzzkit.control.loop_rulebase import check_loop_rulebase

    check_loop_rulebase(rb)
    # the fuzzy-PI clips its inputs to the universe [-1, 1] before evaluating: the surface it
    # sees is the same under either out-of-range policy, and a table needs "clamp"
    rb = replace(rb, out_of_range="clamp")
    if surface.method == "table":
        table = make_table(
            rb, number_type="double", tolerance=surface.tolerance, resolution=surface.resolution
        )
        return SurfaceSource(table_arrays(table), "table", True, 0.0, rb)
    table = make_table(rb, number_type="double", resolution=PROXY_RESOLUTION)
    return SurfaceSource(table_arrays(table), "exact", False, float(table.bound[0]), rb)
