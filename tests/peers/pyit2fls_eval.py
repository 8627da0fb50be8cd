"""Run by ``make interop-refs`` with the `.venv-interop` Python, where pyit2fls 0.9.0 lives.

    python pyit2fls_eval.py eval SYSTEM.json   -> {"y_l": [...], "y_r": [...], "crisp": [...]}
    python pyit2fls_eval.py time SYSTEM.json   -> {"seconds_per_point": s, "crisp": [...]}
    python pyit2fls_eval.py version            -> pyit2fls's version

``time`` (bench/bench_type2.py) evaluates every point once, after one warm-up call, and
reports the mean wall time per point and which back end pyit2fls's Karnik-Mendel ran on.

SYSTEM.json (written by make_it2_refs.py from a fuzzkit IT2 rule base) lists the inputs' and the
output's terms as ``[shape, points, height]`` pairs (upper, lower), the rules (AND only), the
t-norm (pyit2fls uses it for AND and implication), the type-reduction algorithm, the output
domain size and the points. Shapes map to pyit2fls's: triangle -> tri_mf [a, b, c, h],
trapezoid -> trapezoid_mf [a, b, c, d, h], left_shoulder [a, b] -> rtri_mf [b, a, h] (pyit2fls
names it by the side it falls on), right_shoulder [a, b] -> ltri_mf [a, b, h].
"""

from __future__ import annotations

import json
import sys
import time
from importlib.metadata import version

import numpy as np
from pyit2fls import (
    IT2FS,
    IT2Mamdani,
    ltri_mf,
    max_s_norm,
    min_t_norm,
    product_t_norm,
    rtri_mf,
    trapezoid_mf,
    tri_mf,
)


def _mf(shape: str, points: list[float], height: float) -> tuple[object, list[float]]:
    if shape == "triangle":
        return tri_mf, [*points, height]
    if shape == "trapezoid":
        return trapezoid_mf, [*points, height]
    if shape == "left_shoulder":
        return rtri_mf, [points[1], points[0], height]
    if shape == "right_shoulder":
        return ltri_mf, [points[0], points[1], height]
    raise SystemExit(f"shape {shape!r} has no pyit2fls counterpart here")


def _set(domain: np.ndarray, term: dict[str, list]) -> IT2FS:
    umf, up = _mf(term["upper"][0], term["upper"][1], term["upper"][2])
    lmf, lp = _mf(term["lower"][0], term["lower"][1], term["lower"][2])
    return IT2FS(domain, umf, up, lmf, lp)


def _backend() -> str:
    """Which Karnik-Mendel pyit2fls runs: its optional C extension or its Python one."""
    import pyit2fls.pyit2fls as impl

    if getattr(impl, "isThereTypereduction", False):
        return "C extension typereduction"
    return "pure Python/NumPy KM_algorithm (no typereduction C extension)"


def main() -> None:
    if sys.argv[1] == "version":
        sys.stdout.write(version("pyit2fls") + "\n")
        return
    with open(sys.argv[2], encoding="utf-8") as f:
        spec = json.load(f)
    t_norm = {"min": min_t_norm, "product": product_t_norm}[spec["t_norm"]]
    lo, hi = spec["output"]["range"]
    domain = np.linspace(lo, hi, spec["resolution"])
    system = IT2Mamdani(t_norm, max_s_norm, method="Centroid", algorithm=spec["algorithm"])
    sets = {}
    for name, terms in spec["inputs"].items():
        system.add_input_variable(name)
        for label, term in terms.items():
            sets[name, label] = _set(domain, term)
    out = spec["output"]["name"]
    system.add_output_variable(out)
    out_sets = {label: _set(domain, term) for label, term in spec["output"]["terms"].items()}
    for antecedent, consequent in spec["rules"]:
        system.add_rule(
            [(var, sets[var, label]) for var, label in antecedent], [(out, out_sets[consequent])]
        )
    names = list(spec["inputs"])
    n = len(spec["points"][names[0]])
    y_l, y_r, crisp = [], [], []
    if sys.argv[1] == "time":
        system.evaluate({name: spec["points"][name][0] for name in names})
        start = time.perf_counter()
    for k in range(n):
        _, tr = system.evaluate({name: spec["points"][name][k] for name in names})
        value = tr[out]
        if np.size(value) == 2:  # (y_l, y_r): a tuple, or an array from the C extension
            y_l.append(float(value[0]))
            y_r.append(float(value[1]))
            crisp.append(0.5 * (float(value[0]) + float(value[1])))
        else:
            crisp.append(float(value))
    if sys.argv[1] == "time":
        seconds = (time.perf_counter() - start) / n
        json.dump({"seconds_per_point": seconds, "crisp": crisp, "backend": _backend()}, sys.stdout)
        return
    json.dump({"y_l": y_l, "y_r": y_r, "crisp": crisp}, sys.stdout)


if __name__ == "__main__":
    main()
