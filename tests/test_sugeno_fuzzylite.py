"""The Sugeno engine against fuzzylite 6 (the Debian ``fuzzylite`` program) on random points.

The FLL is written by hand for the same system as ``_sugeno_reference.HAND`` (no fuzzkit
exporter is involved); fuzzylite evaluates it with ``-d`` and prints 12 decimals. The live
comparison runs with ``make interop``; ``make test`` compares with fuzzylite's committed
outputs (tests/peers/refs/fuzzylite/sugeno_hand_*.json, ``make interop-refs``).
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import pytest
from _peer_refs import REFS, read_reference
from _peers import FUZZYLITE, needs_fuzzylite
from _sugeno_reference import HAND_FLL_CASES, hand_case_name, hand_doc, hand_fll, hand_points

from fuzzkit.formats.registry import loads
from fuzzkit.fuzzy.inference import Engine


def _ours(defuzz: str, and_: str, or_: str, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    return Engine(loads(hand_doc(defuzz, and_, or_))).evaluate({"x": x, "y": y})["z"]


@needs_fuzzylite
@pytest.mark.parametrize(("defuzz", "and_", "or_", "fl_defuzz", "fl_and", "fl_or"), HAND_FLL_CASES)
def test_engine_matches_fuzzylite(
    tmp_path: Path, defuzz: str, and_: str, or_: str, fl_defuzz: str, fl_and: str, fl_or: str
) -> None:
    assert FUZZYLITE is not None
    (tmp_path / "hand.fll").write_text(hand_fll(fl_defuzz, fl_and, fl_or))
    pts = np.array(hand_points())
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
    assert theirs.shape == (300,)
    # 12 printed decimals (inputs are passed at full precision)
    np.testing.assert_allclose(_ours(defuzz, and_, or_, pts[:, 0], pts[:, 1]), theirs, atol=2e-12)


@pytest.mark.parametrize(("defuzz", "and_", "or_", "fl_defuzz", "fl_and", "fl_or"), HAND_FLL_CASES)
def test_engine_matches_fuzzylites_committed_outputs(
    defuzz: str, and_: str, or_: str, fl_defuzz: str, fl_and: str, fl_or: str
) -> None:
    ref = read_reference(REFS / "fuzzylite" / f"{hand_case_name(defuzz, and_)}_fll.json")
    assert ref.input.read_text() == hand_fll(fl_defuzz, fl_and, fl_or)  # the system fuzzylite ran
    assert ref.points["x"].size == 300
    ours = _ours(defuzz, and_, or_, ref.points["x"], ref.points["y"])
    np.testing.assert_allclose(ours, ref.outputs["z"], rtol=0, atol=2e-12)
