"""Write pyit2fls 0.9.0's outputs for shared interval type-2 systems (``make interop-refs``).

Run with the project's Python; pyit2fls runs in ``.venv-interop`` (``FUZZKIT_INTEROP_PYTHON``)
through tests/peers/pyit2fls_eval.py. Each case is a fuzzkit IT2 rule base (a shipped one or a
file under tests/peers/refs/inputs/), translated here to pyit2fls's sets and rules, one
type-reduction algorithm and one output domain size; the file
``tests/peers/refs/pyit2fls/<case>.json`` holds the points, pyit2fls's ``y_l``/``y_r`` (for the
interval algorithms) and crisp outputs, and the input's SHA-256. tests/test_type2_peers.py
compares fuzzkit's discretised mode (``resolution:`` = the domain size) with them.

pyit2fls evaluates its output sets on the domain ``linspace(low, high, N)`` and type-reduces
the samples (its ``Centroid`` method), as fuzzkit's ``resolution: N`` does; its AND and its
implication are one t-norm, and aggregation is max.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

TESTS = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(TESTS))

from _peer_refs import REFS, ROOT, sha256_of  # noqa: E402

from fuzzkit.formats.registry import load  # noqa: E402
from fuzzkit.fuzzy.model import Proposition, Term, Variable  # noqa: E402
from fuzzkit.fuzzy.type2_model import Type2RuleBase  # noqa: E402

EVAL = Path(__file__).resolve().parent / "pyit2fls_eval.py"
OUT = REFS / "pyit2fls"
#: fuzzkit's type-reduction names -> pyit2fls's algorithm names
ALGORITHMS = {"karnik-mendel": "KM", "ekm": "EKM", "nie-tan": "NT"}
#: (case name, rule-base file, type reduction, domain size)
CASES = (
    (
        "macvicar_whelan_it2_km_101",
        ROOT / "rulebases" / "macvicar_whelan_it2.yaml",
        "karnik-mendel",
        101,
    ),
    (
        "macvicar_whelan_it2_km_1001",
        ROOT / "rulebases" / "macvicar_whelan_it2.yaml",
        "karnik-mendel",
        1001,
    ),
    ("macvicar_whelan_it2_ekm_101", ROOT / "rulebases" / "macvicar_whelan_it2.yaml", "ekm", 101),
    ("macvicar_whelan_it2_nt_101", ROOT / "rulebases" / "macvicar_whelan_it2.yaml", "nie-tan", 101),
    ("it2_small_km_101", REFS / "inputs" / "it2_small.yaml", "karnik-mendel", 101),
    ("it2_small_nt_101", REFS / "inputs" / "it2_small.yaml", "nie-tan", 101),
    ("it2_small_product_km_101", REFS / "inputs" / "it2_small_product.yaml", "karnik-mendel", 101),
    ("it2_small_product_km_501", REFS / "inputs" / "it2_small_product.yaml", "karnik-mendel", 501),
)
N_POINTS = 60


def _term(rb: Type2RuleBase, var: Variable, term: Term) -> dict[str, list[object]]:
    lt = rb.footprint.lower(var.name, term.name)
    lower = (term, 1.0) if lt is None else (lt.shape, lt.scale)
    return {
        "upper": [term.shape, list(term.params), 1.0],
        "lower": [lower[0].shape, list(lower[0].params), lower[1]],
    }


def system_spec(rb: Type2RuleBase, algorithm: str, resolution: int) -> dict[str, object]:
    """The rule base as pyit2fls_eval.py reads it."""
    if rb.operators.and_ != rb.operators.implication:
        raise SystemExit(f"{rb.name}: pyit2fls uses one t-norm for AND and implication")
    out = rb.outputs[0]
    rules = []
    for rule in rb.rules:
        ante = rule.antecedent
        props = [ante] if isinstance(ante, Proposition) else list(ante.operands)
        if rule.weight != 1.0 or not all(isinstance(p, Proposition) for p in props):
            raise SystemExit(f"{rb.name}: pyit2fls takes unweighted AND rules only")
        rules.append(
            [
                [[p.variable, p.term] for p in props if isinstance(p, Proposition)],
                rule.consequents[0].term,
            ]
        )
    return {
        "inputs": {v.name: {t.name: _term(rb, v, t) for t in v.terms} for v in rb.inputs},
        "output": {
            "name": out.name,
            "range": [out.low, out.high],
            "terms": {t.name: _term(rb, out, t) for t in out.terms},
        },
        "rules": rules,
        "t_norm": rb.operators.and_,
        "algorithm": ALGORITHMS[algorithm],
        "resolution": resolution,
    }


def points(rb: Type2RuleBase, seed: int) -> dict[str, list[float]]:
    """Random points inside the ranges (pyit2fls does not clamp), plus the centre."""
    rng = np.random.default_rng(seed)
    return {
        v.name: [0.5 * (v.low + v.high), *rng.uniform(v.low, v.high, N_POINTS - 1).tolist()]
        for v in rb.inputs
    }


def main() -> int:
    python = os.environ.get(
        "FUZZKIT_INTEROP_PYTHON", str(ROOT / ".venv-interop" / "bin" / "python")
    )
    version = subprocess.run(
        [python, str(EVAL), "version"], check=True, capture_output=True, text=True
    ).stdout.strip()
    OUT.mkdir(parents=True, exist_ok=True)
    for seed, (name, path, method, resolution) in enumerate(CASES):
        rb = load(path)
        if not isinstance(rb, Type2RuleBase):
            raise SystemExit(f"{path}: not an interval type-2 rule base")
        spec = system_spec(rb, method, resolution)
        spec["points"] = points(rb, seed)
        with tempfile.TemporaryDirectory() as tmp:
            spec_path = Path(tmp) / "system.json"
            spec_path.write_text(json.dumps(spec), encoding="utf-8")
            got = json.loads(
                subprocess.run(
                    [python, str(EVAL), "eval", str(spec_path)],
                    check=True,
                    capture_output=True,
                    text=True,
                ).stdout
            )
        doc = {
            "peer": "pyit2fls",
            "peer_version": version,
            "input": path.relative_to(ROOT).as_posix(),
            "input_sha256": sha256_of(path),
            "type_reduction": method,
            "algorithm": ALGORITHMS[method],
            "resolution": resolution,
            "points": spec["points"],
            "outputs": got,
        }
        (OUT / f"{name}.json").write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
        print(f"{name}: {len(got['crisp'])} points")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
