"""Benchmark: the interval type-2 engine beside pyit2fls 0.9.0, and the generated IT2 step.

``macvicar_whelan_it2`` (49 rules, Karnik-Mendel). Rows:

* fuzzkit's exact IT2 engine (continuous type reduction, the compiled kernel of
  ``fuzzkit/fuzzy/type2_kernel.py``): one scalar point (``Engine.evaluate_point``) and a
  101x101 surface (one ``evaluate``);
* pyit2fls 0.9.0 (``--peers-python``: an environment holding it, ``make bench`` installs it in
  ``.venv-bench``), Karnik-Mendel on a 101-point output domain: mean time per point over an
  11x11 grid, and the 101x101 surface extrapolated from it (10201 x the per-point time; the
  peer evaluates one point per call, so the extrapolation is its real cost to within the
  machine's noise). Its value at the scalar point is printed beside fuzzkit's exact one and
  fuzzkit's ``resolution: 101`` one (which is pyit2fls's number to rounding). The back end
  pyit2fls ran (its optional C ``typereduction`` extension or its Python KM) is printed;
* the generated controller: the IT2 surface as a C float lookup table (65x65, its certified
  bound against the exact engine printed), ns per ``NAME_eval`` (the harness of
  bench_codegen.py, -O2, CPU-time clock) and per 3-axis step (3 evals).

* the generated exact IT2 code (``--method exact``, C float and double, -O2): bytes, largest
  error against the engine, ns per eval and per 3-axis step.

Target (issues 32, 43): the engine 100x faster than pyit2fls; the generated step <= 1 us (3 axes).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

import fuzzkit
from fuzzkit.codegen.exact import emit_exact
from fuzzkit.codegen.table_search import make_table
from fuzzkit.fuzzy.inference import Engine

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(ROOT / "tests" / "peers"))
sys.path.insert(0, str(ROOT / "tests"))

from bench_codegen import c_ns_per_call, measure_files  # noqa: E402
from bench_engine import best_of  # noqa: E402
from make_it2_refs import EVAL, system_spec  # noqa: E402

NAME = "macvicar_whelan_it2"
POINT = (0.3, -0.2)
SURFACE_N = 101
PEER_GRID = 11
TABLE_RESOLUTION = 65
#: Calls the exact step's timing makes (it is microseconds a call, the table's nanoseconds).
EXACT_CALLS = 20_000


def peer_row(python: str, rb: fuzzkit.fuzzy.model.RuleBase) -> tuple[float, float, str]:  # type: ignore[name-defined]
    """(seconds per point, value at POINT, back end) of pyit2fls."""
    g = np.linspace(-1.0, 1.0, PEER_GRID)
    ge, gd = np.meshgrid(g, g, indexing="ij")
    spec = system_spec(rb, "karnik-mendel", 101)
    spec["points"] = {"e": [POINT[0], *ge.ravel().tolist()], "de": [POINT[1], *gd.ravel().tolist()]}
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "system.json"
        path.write_text(json.dumps(spec), encoding="utf-8")
        out = subprocess.run(
            [python, str(EVAL), "time", str(path)], check=True, capture_output=True, text=True
        ).stdout
    got = json.loads(out)
    return float(got["seconds_per_point"]), float(got["crisp"][0]), str(got["backend"])


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--peers-python", help="python of an environment holding pyit2fls 0.9.0")
    args, _ = ap.parse_known_args(argv)
    rb = fuzzkit.load(NAME)
    eng = Engine(rb)
    g = np.linspace(-1.0, 1.0, SURFACE_N)
    ge, gd = np.meshgrid(g, g, indexing="ij")
    scalar = best_of(lambda: eng.evaluate_point(e=POINT[0], de=POINT[1]))
    surface = best_of(lambda: eng.evaluate({"e": ge, "de": gd}), repeat=3, min_time=0.0)
    value = eng.evaluate_point(e=POINT[0], de=POINT[1])["du"]
    fp = replace(rb.footprint, resolution=101)  # type: ignore[attr-defined]
    value101 = Engine(replace(rb, footprint=fp)).evaluate_point(e=POINT[0], de=POINT[1])["du"]
    print(f"{NAME}: exact IT2 engine (continuous Karnik-Mendel), point {POINT}")
    print(f"  {'who':<44} {'scalar':>10} {'101x101':>10}  value")
    print(f"  {'fuzzkit exact':<44} {scalar * 1e3:>8.2f}ms {surface:>9.2f}s  {value:.10f}")
    print(f"  {'fuzzkit resolution: 101':<44} {'':>10} {'':>10}  {value101:.10f}")
    if args.peers_python:
        per_point, peer_value, backend = peer_row(args.peers_python, rb)
        print(
            f"  {'pyit2fls 0.9.0 KM, 101-point domain':<44} {per_point * 1e3:>8.2f}ms "
            f"{per_point * SURFACE_N**2:>9.1f}s  {peer_value:.10f}"
        )
        print(
            f"  fuzzkit / pyit2fls speed: scalar {per_point / scalar:.0f}x, "
            f"surface {per_point * SURFACE_N**2 / surface:.0f}x (pyit2fls surface extrapolated "
            f"from {PEER_GRID}x{PEER_GRID} points; target 100x)"
        )
        print(f"  pyit2fls back end: {backend}")
    start = time.perf_counter()
    table = make_table(rb, number_type="float", resolution=TABLE_RESOLUTION)
    built = time.perf_counter() - start
    out = rb.outputs[0]
    bound = table.bound[0] / (out.high - out.low)
    ns = c_ns_per_call(rb, table)
    print(
        f"generated C float table {TABLE_RESOLUTION}x{TABLE_RESOLUTION}: certified bound "
        f"{bound:.2%} of the output range against the exact engine (built in {built:.0f} s)"
    )
    if ns is None:
        print("  no C compiler: step not timed")
    else:
        print(f"  {ns:.1f} ns per eval, {3 * ns:.1f} ns per 3-axis step (target <= 1000 ns)")
        for number_type in ("float", "double"):
            nbytes, ns, err = measure_files(
                rb, emit_exact(rb, "c", number_type), number_type, EXACT_CALLS
            )
            print(
                f"generated C {number_type} exact IT2 (--method exact, -O2): {nbytes} bytes of "
                f"code and constants, largest error {err:.2g} of the output range"
            )
            print(f"  {ns:.0f} ns per eval, {3 * ns:.0f} ns per 3-axis step (target <= 1000 ns)")


if __name__ == "__main__":
    main(sys.argv[1:])
