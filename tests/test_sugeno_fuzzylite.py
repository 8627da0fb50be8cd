"""The Sugeno engine against fuzzylite 6 (the Debian ``fuzzylite`` program) on random points.

The FLL below is written by hand for the same system as ``_sugeno_reference.HAND`` (no fuzzkit
exporter is involved); fuzzylite evaluates it with ``-d`` and prints 12 decimals.
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from _sugeno_reference import hand_doc

from fuzzkit.formats.registry import loads
from fuzzkit.fuzzy.inference import Engine

FUZZYLITE = shutil.which("fuzzylite")
pytestmark = [
    pytest.mark.needs_fuzzylite,
    pytest.mark.skipif(FUZZYLITE is None, reason="fuzzylite 6 not found (apt install fuzzylite)"),
]

FLL = """\
Engine: hand
InputVariable: x
  enabled: true
  range: 0.000 10.000
  lock-range: true
  term: lo Ramp 8.000 2.000
  term: hi Ramp 2.000 8.000
InputVariable: y
  enabled: true
  range: 0.000 1.000
  lock-range: true
  term: small Triangle -1.000 0.000 1.000
  term: big Triangle 0.000 1.000 2.000
OutputVariable: z
  enabled: true
  range: -10.000 10.000
  lock-range: false
  aggregation: none
  defuzzifier: {defuzzifier} TakagiSugeno
  default: nan
  lock-previous: false
  term: A Constant 4.000
  term: B Linear 0.500 -2.000 1.000
RuleBlock: rb
  enabled: true
  conjunction: {conjunction}
  disjunction: {disjunction}
  implication: none
  activation: General
  rule: if x is lo and y is small then z is A
  rule: if x is hi or y is big then z is B with 0.5
  rule: if x is not lo then z is A
"""

CASES = [
    ("weighted_average", "min", "max", "WeightedAverage", "Minimum", "Maximum"),
    ("weighted_sum", "min", "max", "WeightedSum", "Minimum", "Maximum"),
    (
        "weighted_average",
        "product",
        "probabilistic_sum",
        "WeightedAverage",
        "AlgebraicProduct",
        "AlgebraicSum",
    ),
]


@pytest.mark.parametrize(("defuzz", "and_", "or_", "fl_defuzz", "fl_and", "fl_or"), CASES)
def test_engine_matches_fuzzylite(
    tmp_path: Path, defuzz: str, and_: str, or_: str, fl_defuzz: str, fl_and: str, fl_or: str
) -> None:
    assert FUZZYLITE is not None
    (tmp_path / "hand.fll").write_text(
        FLL.format(defuzzifier=fl_defuzz, conjunction=fl_and, disjunction=fl_or)
    )
    pts = np.random.default_rng(6).uniform([-1.0, -0.2], [11.0, 1.2], (300, 2))
    rows = "\n".join(f"{x!r} {y!r}" for x, y in pts.tolist())
    (tmp_path / "in.fld").write_text("x y\n" + rows + "\n")
    command = [FUZZYLITE, "-i", "hand.fll", "-if", "fll", "-o", "out.fld", "-of", "fld"]
    subprocess.run(
        [*command, "-d", "in.fld", "-decimals", "12"],
        cwd=tmp_path,
        check=True,
        capture_output=True,
        timeout=60,
    )
    lines = (tmp_path / "out.fld").read_text().split("\n")
    theirs = np.array([float(line.split()[2]) for line in lines[1:] if line.strip()])
    ours = Engine(loads(hand_doc(defuzz, and_, or_))).evaluate({"x": pts[:, 0], "y": pts[:, 1]})
    assert theirs.shape == (300,)
    # 12 printed decimals (inputs are passed at full precision)
    np.testing.assert_allclose(ours["z"], theirs, rtol=0, atol=2e-12)
