"""Largest differences between fuzzkit and fuzzylite 6 / pyfuzzylite 8, per format and direction.

Run by ``make interop`` after the equivalence tests: the same comparisons on more random rule
bases (every defuzzifier, operator, NOT, OR, weights, 1-3 inputs, 1-2 outputs, points up to
10 % beyond the input ranges) and on the shipped examples, printed as a table. Differences are
fractions of the output range; for the maxima defuzzifiers the points where fuzzylite picks
another, nearly equal maximum (see tests/test_interop_peers.py) are counted, not measured.
"""

from __future__ import annotations

import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))

from _peers import (  # noqa: E402
    FUZZYLITE,
    RESOLUTION,
    _has_pyfuzzylite,
    fuzzylite_convert,
    fuzzylite_eval,
    peer_points,
    pyfuzzylite_eval,
    pyfuzzylite_export,
)
from _random_rulebases import MAXIMA, random_rulebase  # noqa: E402

from fuzzkit.formats import fcl, fis, fll  # noqa: E402
from fuzzkit.formats.registry import load  # noqa: E402
from fuzzkit.fuzzy.inference import evaluate  # noqa: E402
from fuzzkit.fuzzy.model import RuleBase  # noqa: E402

SEEDS = range(16)
EXAMPLES = ["heater.fis", "gripper_iec.fcl", "gripper_named.fcl", "feed.fll"]


class Row:
    """Running figures of one (peer, direction, format, defuzzifier family) cell."""

    def __init__(self) -> None:
        self.systems = 0
        self.points = 0
        self.worst = 0.0
        self.ties = 0

    def add(self, rb: RuleBase, ours: dict[str, np.ndarray], theirs: dict[str, np.ndarray]) -> None:
        self.systems += 1
        for var in rb.outputs:
            diff = np.abs(ours[var.name] - theirs[var.name]) / (var.high - var.low)
            if rb.defuzzifier in MAXIMA:
                tie = diff > 2.0 / RESOLUTION
                self.ties += int(tie.sum())
                diff = diff[~tie]
            self.points += diff.size
            self.worst = max(self.worst, float(np.max(diff, initial=0.0)))


def main() -> int:
    rows: dict[tuple[str, str, str, str], Row] = {}

    def row(peer: str, direction: str, fmt: str, rb: RuleBase) -> Row:
        family = (
            "centroid"
            if rb.defuzzifier == "centroid"
            else ("bisector" if rb.defuzzifier == "bisector" else "maxima")
        )
        return rows.setdefault((peer, direction, fmt, family), Row())

    writers: dict[str, Callable[[RuleBase], str]] = {
        "fis": lambda rb: fis.dumps(rb),
        "fcl": lambda rb: fcl.dumps(rb),
        "fll": lambda rb: fll.dumps(rb),
    }
    systems = [random_rulebase(s) for s in SEEDS] + [
        load(ROOT / "docs/examples" / e) for e in EXAMPLES
    ]
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        for k, rb in enumerate(systems):
            points = peer_points(rb, k)
            ours = evaluate(rb, points)
            if FUZZYLITE is not None:
                for fmt, write in writers.items():
                    if fmt == "fis" and fis.refusals(rb):
                        continue
                    if fmt != "fll" and {"fis": fis.losses, "fcl": fcl.losses}[fmt](rb):
                        continue  # a clamped example: .fis and FCL cannot clamp
                    path = tmp / f"x.{fmt}"
                    path.write_text(write(rb))
                    row("fuzzylite 6", "fuzzkit writes", fmt, rb).add(
                        rb, ours, fuzzylite_eval(path, fmt, points, tmp)
                    )
                    src = tmp / "src.fll"
                    src.write_text(fll.dumps(rb))
                    if fmt == "fis" and fis.refusals(rb):
                        continue
                    theirs = fuzzylite_convert(src, "fll", tmp / f"by_fuzzylite.{fmt}")
                    imported = load(theirs)
                    row("fuzzylite 6", "fuzzkit reads", fmt, rb).add(
                        imported,
                        evaluate(imported, points),
                        fuzzylite_eval(theirs, fmt, points, tmp),
                    )
            if _has_pyfuzzylite():
                path = tmp / "x.fll"
                path.write_text(fll.dumps(rb).replace(f" {fll.RESOLUTION}", f" {RESOLUTION}"))
                row("pyfuzzylite 8", "fuzzkit writes", "fll", rb).add(
                    rb, ours, pyfuzzylite_eval(path, points, tmp)
                )
                theirs_path = tmp / "by_pyfuzzylite.fll"
                theirs_path.write_text(pyfuzzylite_export(path))
                imported = load(theirs_path)
                row("pyfuzzylite 8", "fuzzkit reads", "fll", rb).add(
                    imported, evaluate(imported, points), pyfuzzylite_eval(theirs_path, points, tmp)
                )
    print(
        f"{'peer':14} {'direction':15} {'fmt':4} {'defuzzifier':12} {'systems':>7} "
        f"{'points':>7} {'largest diff':>12} {'near ties':>9}"
    )
    for (peer, direction, fmt, family), r in sorted(rows.items()):
        print(
            f"{peer:14} {direction:15} {fmt:4} {family:12} {r.systems:7d} {r.points:7d} "
            f"{r.worst:12.2e} {r.ties:9d}"
        )
    print(f"(differences as fractions of the output range; peers integrate on {RESOLUTION} steps)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
