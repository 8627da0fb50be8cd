"""The exact C centroid evaluates only the functions the 2 x 2 firing cells can make non-zero.

With two partition inputs, the generated code locates the block of cells that can fire from
its first cell (i0, j0) and sums the centroid's area and moment over that block's set of
functions (a table per output) instead of over all of them. Checked on seeded random rule
tables over random partitions (cells left empty, consequents in any order):

- every function whose level is non-zero at a point is in the set of the point's block, with
  the levels computed here from the memberships and the rule table (not from the generator's
  sets), at every term peak, one ulp either side of it, and halfway between peaks;
- the generated C matches the exact engine to the stated rounding bound: in double on every
  table, in float on full tables. (With empty cells the output jumps, to another term or to
  the default, where the only firing rule's membership crosses 0; float rounding of the
  memberships moves those jumps, so float is only comparable where no cell is empty. That was
  so before the firing sets too: the float code is bit-identical to the code that summed
  every function.)
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from _codegen_util import needs_cc, skip_no_cc

from fuzzkit.codegen.exact import build_exact_spec, emit_exact
from fuzzkit.codegen.verify import verify_exact_c
from fuzzkit.fuzzy.membership import evaluate_term
from fuzzkit.fuzzy.model import Compound, Consequent, Proposition, Rule, RuleBase, Variable
from fuzzkit.fuzzy.partition import PARTITION_ENDS, partition_terms
from fuzzkit.fuzzy.validation import check


def random_table(seed: int, gaps: bool = True) -> RuleBase:
    """Two partition inputs, a partition output, a random rule table (a fifth of it empty with
    ``gaps``)."""
    rng = np.random.default_rng(seed)
    inputs = []
    for k, name in enumerate(("e", "de")):
        n = int(rng.integers(2, 9))
        low = round(float(rng.uniform(-20.0, 5.0)), 2)
        high = round(low + float(rng.uniform(0.5, 30.0)), 2)
        labels = [f"{name.upper()}{i}" for i in range(n)]
        inputs.append(
            Variable(
                name, low, high, partition_terms(labels, low, high, PARTITION_ENDS[(seed + k) % 2])
            )
        )
    out_labels = [f"U{i}" for i in range(int(rng.integers(2, 8)))]
    out = Variable("u", -3.0, 3.0, partition_terms(out_labels, -3.0, 3.0, "triangle"))
    rules = []
    for i, j in itertools.product(range(len(inputs[0].terms)), range(len(inputs[1].terms))):
        if rng.random() < 0.8 or not gaps:
            ante = Compound(
                "and",
                (
                    Proposition("e", inputs[0].terms[i].name),
                    Proposition("de", inputs[1].terms[j].name),
                ),
            )
            rules.append(Rule(ante, (Consequent("u", str(rng.choice(out_labels))),)))
    rb = RuleBase(name=f"cells{seed}", inputs=tuple(inputs), outputs=(out,), rules=tuple(rules))
    assert check(rb) == []
    return rb


SEEDS = range(12)


def probe_values(var: Variable) -> list[float]:
    """Every term peak, one ulp either side of it (inside the range) and halfway between peaks."""
    peaks = sorted(
        {float(t.params[0] if t.shape == "left_shoulder" else t.params[1]) for t in var.terms}
    )
    values = set(peaks)
    for p in peaks:
        values.update(
            v
            for v in (np.nextafter(p, -np.inf), np.nextafter(p, np.inf))
            if var.low <= v <= var.high
        )
    values.update(0.5 * (a + b) for a, b in itertools.pairwise(peaks))
    return sorted(values)


def ints(rows: tuple[str, ...]) -> list[int]:
    return [int(v) for row in rows for v in row.rstrip(",").split(",") if v.strip()]


@pytest.mark.parametrize("seed", SEEDS)
def test_every_non_zero_function_is_in_its_blocks_set(seed: int) -> None:
    rb = random_table(seed)
    spec = build_exact_spec(rb, "c", "double")
    assert len(spec.windows) == 2
    poly = spec.outputs[0].poly
    assert poly is not None and poly.set_width > 0
    columns = len(rb.inputs[1].terms) + 1
    block_set = ints(poly.block_set)
    funcs = ints(poly.set_funcs)
    counts = [int(c) for c in poly.set_count]
    sets = [set(funcs[s * poly.set_width : s * poly.set_width + c]) for s, c in enumerate(counts)]
    level_a, level_b = [int(v) for v in poly.level_a], [int(v) for v in poly.level_b]
    cuts = [[float(c.rstrip("f")) for c in w.cuts] for w in spec.windows]
    first = [[int(f) for f in w.first] for w in spec.windows]
    cons = {
        (
            rb.inputs[0].term_index(r.antecedent.operands[0].term),
            rb.inputs[1].term_index(r.antecedent.operands[1].term),
        ): rb.outputs[0].term_index(r.consequents[0].term)
        for r in rb.rules
        if isinstance(r.antecedent, Compound)
        and isinstance(r.antecedent.operands[0], Proposition)
        and isinstance(r.antecedent.operands[1], Proposition)
    }
    assert len(cons) == len(rb.rules)
    checked = 0
    for x0, x1 in itertools.product(probe_values(rb.inputs[0]), probe_values(rb.inputs[1])):
        mu0 = [float(evaluate_term(t, x0)) for t in rb.inputs[0].terms]
        mu1 = [float(evaluate_term(t, x1)) for t in rb.inputs[1].terms]
        level: dict[int, float] = {}
        for (i, j), t in cons.items():
            level[t] = max(level.get(t, 0.0), min(mu0[i], mu1[j]))
        live = {
            f
            for f, (a, b) in enumerate(zip(level_a, level_b, strict=True))
            if min(level.get(a, 0.0), level.get(b, 0.0)) > 0.0
        }
        i0 = first[0][sum(x0 >= c for c in cuts[0])]
        j0 = first[1][sum(x1 >= c for c in cuts[1])]
        assert live <= sets[block_set[i0 * columns + j0]], (seed, x0, x1, live)
        checked += bool(live)
    assert checked > 0


@needs_cc
@skip_no_cc
@pytest.mark.parametrize(("number_type", "gaps"), [("double", True), ("float", False)])
def test_random_rule_tables_in_c_match_the_engine_to_rounding(number_type: str, gaps: bool) -> None:
    for seed in SEEDS:
        rb = random_table(seed, gaps)
        result = verify_exact_c(rb, number_type, emit_exact(rb, "c", number_type), n=2000)
        assert result.ok, (seed, result.describe())
