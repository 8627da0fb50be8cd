"""Time peer fuzzy-logic libraries on a two-input table rule base given as JSON on stdin.

Runs in the separate benchmark environment (``.venv-bench``): it imports nothing from
fuzzkit. The spec is written by ``bench_engine.py`` from the very model fuzzkit evaluates, so
every library runs the same rule base. Prints one JSON object: ``{library: {...}}``.
"""

from __future__ import annotations

import json
import sys
import time
import warnings
from typing import Any

import numpy as np

warnings.filterwarnings("ignore")


def _timeit(fn: Any, min_time: float = 0.5, max_calls: int = 10_000) -> float:
    fn()  # warm up
    calls, start = 0, time.perf_counter()
    while True:
        fn()
        calls += 1
        elapsed = time.perf_counter() - start
        if elapsed >= min_time or calls >= max_calls:
            return elapsed / calls


def _grid(spec: dict[str, Any], n: int) -> tuple[np.ndarray, np.ndarray]:
    (lo0, hi0), (lo1, hi1) = (v["range"] for v in spec["inputs"])
    return np.meshgrid(np.linspace(lo0, hi0, n), np.linspace(lo1, hi1, n), indexing="ij")


def bench_skfuzzy(spec: dict[str, Any], point: list[float], n: int) -> dict[str, Any]:
    import skfuzzy as fuzz
    from skfuzzy import control as ctrl

    out_var = spec["outputs"][0]
    lo, hi = out_var["range"]
    step = (hi - lo) / 2000
    # the universe must end exactly on the range end, or the outer peak is silently lost
    universe = np.round(np.arange(lo, hi + step / 2, step), 12)

    def add_terms(sk: Any, var: dict[str, Any]) -> None:
        for name, shape, p in var["terms"]:
            if shape == "triangle":
                sk[name] = fuzz.trimf(universe, p)
            elif shape == "trapezoid":
                sk[name] = fuzz.trapmf(universe, p)
            elif shape == "left_shoulder":
                sk[name] = fuzz.trapmf(universe, [p[0] - 1e3, p[0] - 1e3, p[0], p[1]])
            elif shape == "right_shoulder":
                sk[name] = fuzz.trapmf(universe, [p[0], p[1], p[1] + 1e3, p[1] + 1e3])
            else:
                raise SystemExit(f"skfuzzy bench: shape {shape} not mapped")

    ants = []
    for var in spec["inputs"]:
        a = ctrl.Antecedent(universe, var["name"])
        add_terms(a, var)
        ants.append(a)
    cons = ctrl.Consequent(universe, out_var["name"], defuzzify_method="centroid")
    add_terms(cons, out_var)
    rules = [ctrl.Rule(ants[0][r[0]] & ants[1][r[1]], cons[r[2]]) for r in spec["rules"]]
    # no result cache: a benchmark that repeats one input would otherwise time a dict lookup
    system = ctrl.ControlSystem(rules)
    sim = ctrl.ControlSystemSimulation(system, cache=False, flush_after_run=10**9)
    names = [v["name"] for v in spec["inputs"]]

    def one(x: float, y: float) -> float:
        sim.input[names[0]] = x
        sim.input[names[1]] = y
        sim.compute()
        return float(sim.output[out_var["name"]])

    scalar = _timeit(lambda: one(*point), min_time=1.0, max_calls=200)
    gx, gy = _grid(spec, n)
    start = time.perf_counter()
    batch = ctrl.ControlSystemSimulation(system, cache=False)
    batch.input[names[0]] = gx.ravel()  # skfuzzy 0.5 accepts arrays: one batched compute
    batch.input[names[1]] = gy.ravel()
    batch.compute()
    surface = time.perf_counter() - start
    return {
        "version": fuzz.__version__,
        "scalar_s": scalar,
        "surface_s": surface,
        "value": one(*point),
        "surface_mode": "array input",
    }


def _fll(spec: dict[str, Any]) -> str:
    def term(name: str, shape: str, p: list[float]) -> str:
        if shape == "triangle":
            return f"  term: {name} Triangle {p[0]!r} {p[1]!r} {p[2]!r}"
        if shape == "trapezoid":
            return f"  term: {name} Trapezoid {p[0]!r} {p[1]!r} {p[2]!r} {p[3]!r}"
        if shape == "left_shoulder":
            return f"  term: {name} Ramp {p[1]!r} {p[0]!r}"
        if shape == "right_shoulder":
            return f"  term: {name} Ramp {p[0]!r} {p[1]!r}"
        raise SystemExit(f"fuzzylite bench: shape {shape} not mapped")

    lines = [f"Engine: {spec['name']}"]
    for v in spec["inputs"]:
        lines += [
            f"InputVariable: {v['name']}",
            "  enabled: true",
            f"  range: {v['range'][0]!r} {v['range'][1]!r}",
            "  lock-range: true",
        ]
        lines += [term(*t) for t in v["terms"]]
    o = spec["outputs"][0]
    lines += [
        f"OutputVariable: {o['name']}",
        "  enabled: true",
        f"  range: {o['range'][0]!r} {o['range'][1]!r}",
        "  lock-range: false",
        "  aggregation: Maximum",
        "  defuzzifier: Centroid",
        "  default: nan",
        "  lock-previous: false",
    ]
    lines += [term(*t) for t in o["terms"]]
    lines += [
        "RuleBlock: rules",
        "  enabled: true",
        "  conjunction: Minimum",
        "  disjunction: Maximum",
        "  implication: Minimum",
        "  activation: General",
    ]
    names = [v["name"] for v in spec["inputs"]]
    lines += [
        f"  rule: if {names[0]} is {a} and {names[1]} is {b} then {o['name']} is {c}"
        for a, b, c in spec["rules"]
    ]
    return "\n".join(lines) + "\n"


def bench_fuzzylite(spec: dict[str, Any], point: list[float], n: int) -> dict[str, Any]:
    import fuzzylite as fl

    engine = fl.FllImporter().from_string(_fll(spec))
    names = [v["name"] for v in spec["inputs"]]
    out = engine.output_variable(spec["outputs"][0]["name"])

    def run(x: Any, y: Any) -> Any:
        engine.input_variable(names[0]).value = x
        engine.input_variable(names[1]).value = y
        engine.process()
        return out.value

    scalar = _timeit(lambda: run(*point))
    gx, gy = _grid(spec, n)
    start = time.perf_counter()
    run(gx.ravel(), gy.ravel())  # pyfuzzylite 8 accepts arrays
    surface = time.perf_counter() - start
    resolution = getattr(out.defuzzifier, "resolution", "?")
    return {
        "version": fl.__version__,
        "scalar_s": scalar,
        "surface_s": surface,
        "value": float(np.asarray(run(*point)).reshape(-1)[0]),
        "surface_mode": f"array input, centroid resolution {resolution}",
    }


def main() -> None:
    spec = json.load(sys.stdin)
    point, n = spec["point"], spec["surface_n"]
    results: dict[str, Any] = {}
    for name, fn in (("scikit-fuzzy", bench_skfuzzy), ("pyfuzzylite", bench_fuzzylite)):
        try:
            results[name] = fn(spec, point, n)
        except Exception as exc:  # a peer failing must not hide the others' figures
            results[name] = {"error": f"{type(exc).__name__}: {exc}"}
    json.dump(results, sys.stdout)


if __name__ == "__main__":
    main()
