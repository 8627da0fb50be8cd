"""Benchmark: fuzzkit's exact engine against scikit-fuzzy and pyfuzzylite on MacVicar-Whelan.

Prints scalar evaluation time (us) and a 101x101 control surface (ms) for each, with the
ratio to fuzzkit and the value each computes at the scalar point (centroid, so the peers'
discretisation shows). The peers run in a separate environment (``--peers-python``).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

import fuzzkit
from fuzzkit.fuzzy.inference import Engine

POINT = (0.3, -0.2)
SURFACE_N = 101
TARGET_SCALAR_US = 20.0
TARGET_SURFACE_MS = 20.0


def best_of(fn: Callable[[], object], repeat: int = 5, min_time: float = 0.2) -> float:
    """Best mean time per call over ``repeat`` batches of at least ``min_time`` seconds."""
    fn()
    calls = 1
    while True:
        start = time.perf_counter()
        for _ in range(calls):
            fn()
        if time.perf_counter() - start >= min_time:
            break
        calls *= 2
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        for _ in range(calls):
            fn()
        best = min(best, (time.perf_counter() - start) / calls)
    return best


def peer_spec(rb: fuzzkit.fuzzy.model.RuleBase) -> dict[str, Any]:  # type: ignore[name-defined]
    def var(v: Any) -> dict[str, Any]:
        return {
            "name": v.name,
            "range": [v.low, v.high],
            "terms": [[t.name, t.shape, list(t.params)] for t in v.terms],
        }

    rules = []
    for r in rb.rules:
        a, b = r.antecedent.operands
        rules.append([a.term, b.term, r.consequents[0].term])
    return {
        "name": rb.name,
        "inputs": [var(v) for v in rb.inputs],
        "outputs": [var(v) for v in rb.outputs],
        "rules": rules,
        "point": list(POINT),
        "surface_n": SURFACE_N,
    }


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--peers-python", help="python of the environment holding the peers")
    args, _ = ap.parse_known_args(argv)

    rb = fuzzkit.load("macvicar_whelan")
    eng = Engine(rb)
    g = np.linspace(-1.0, 1.0, SURFACE_N)
    ge, gde = np.meshgrid(g, g, indexing="ij")
    rows: list[tuple[str, float, float, float, str]] = []
    ours_scalar = best_of(lambda: eng.evaluate_point(e=POINT[0], de=POINT[1]))
    ours_surface = best_of(lambda: eng.evaluate({"e": ge, "de": gde}), repeat=5, min_time=0.3)
    ours_value = eng.evaluate_point(e=POINT[0], de=POINT[1])["du"]
    rows.append(
        (
            "fuzzkit " + fuzzkit.__version__ + " (exact)",
            ours_scalar,
            ours_surface,
            ours_value,
            "batch (numpy)",
        )
    )

    if args.peers_python and Path(args.peers_python).exists():
        proc = subprocess.run(
            [args.peers_python, str(Path(__file__).with_name("peers_fuzzy.py"))],
            input=json.dumps(peer_spec(rb)),
            capture_output=True,
            text=True,
            check=False,
        )
        if proc.returncode != 0:
            print(f"peer benchmark failed:\n{proc.stderr[-2000:]}")
        else:
            for name, res in json.loads(proc.stdout).items():
                if "error" in res:
                    print(f"{name}: {res['error']}")
                    continue
                rows.append(
                    (
                        f"{name} {res['version']}",
                        res["scalar_s"],
                        res["surface_s"],
                        res["value"],
                        res["surface_mode"],
                    )
                )
    else:
        print("(peers not measured: pass --peers-python, as `make bench` does)")

    print(
        f"\nExact engine vs peers, MacVicar-Whelan 7x7, scalar at (e, de) = {POINT}, "
        f"surface {SURFACE_N}x{SURFACE_N}"
    )
    head = (
        f"{'library':<28} {'scalar us':>10} {'x fuzzkit':>9} {'surface ms':>11} "
        f"{'x fuzzkit':>9} {'du at point':>14}  surface mode"
    )
    print(head)
    print("-" * len(head))
    for name, sc, sf, val, mode in rows:
        print(
            f"{name:<28} {sc * 1e6:>10.1f} {sc / ours_scalar:>9.1f} {sf * 1e3:>11.1f} "
            f"{sf / ours_surface:>9.1f} {val:>14.10f}  {mode}"
        )
    ok_s = ours_scalar * 1e6 <= TARGET_SCALAR_US
    ok_f = ours_surface * 1e3 <= TARGET_SURFACE_MS
    print(
        f"targets: scalar <= {TARGET_SCALAR_US:.0f} us: {'met' if ok_s else 'MISSED'} "
        f"({ours_scalar * 1e6:.1f}); surface <= {TARGET_SURFACE_MS:.0f} ms: "
        f"{'met' if ok_f else 'MISSED'} ({ours_surface * 1e3:.1f})"
    )


if __name__ == "__main__":
    main()
