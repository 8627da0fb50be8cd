"""Write the peers' reference outputs under tests/peers/refs/ (``make interop-refs``).

Needs the fuzzylite program and pyfuzzylite in ``.venv-interop`` (``make interop-refs``
installs both); run with the project's Python. Every input file a peer reads is either a file
of ``docs/examples/`` or is written here under ``tests/peers/refs/inputs/`` and committed, so
the comparison in ``make test`` (tests/test_peer_refs.py) depends on neither the random
rule-base generator nor fuzzkit's writers of today. Cases:

* fuzzylite 6: every example in its own format (the IEC example in the spelling fuzzylite
  accepts: it refuses the example's comments); the Mamdani examples as fuzzylite re-writes
  them in FIS, FCL and FLL (files the peer writes, fuzzkit reads); :data:`N_RANDOM` random
  rule bases per format as fuzzkit writes them; :data:`N_RANDOM_CONVERTED` random rule bases
  per format as fuzzylite re-writes them; the hand-written Sugeno FLL of
  ``_sugeno_reference``;
* pyfuzzylite 8 (FLL only): every example as fuzzkit writes it in FLL and as pyfuzzylite
  re-writes that; :data:`N_RANDOM` random rule bases (clamped and extended in turn).
"""

from __future__ import annotations

import shutil
import sys
import tempfile
import zlib
from pathlib import Path

import numpy as np

TESTS = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(TESTS))

from _peer_refs import INPUTS, REFS, ROOT, FloatArray, write_reference  # noqa: E402
from _peers import (  # noqa: E402
    FUZZYLITE,
    N_POINTS,
    RESOLUTION,
    fuzzylite_convert,
    fuzzylite_eval,
    fuzzylite_version,
    peer_points,
    pyfuzzylite_eval,
    pyfuzzylite_export,
    pyfuzzylite_version,
)
from _random_rulebases import random_rulebase  # noqa: E402
from _sugeno_reference import (  # noqa: E402
    HAND_FLL_CASES,
    hand_case_name,
    hand_fll,
    hand_points,
)

from fuzzkit import __version__ as fuzzkit_version  # noqa: E402
from fuzzkit.formats import fcl, fis, fll  # noqa: E402
from fuzzkit.formats.registry import dumps, load  # noqa: E402
from fuzzkit.fuzzy.model import RuleBase  # noqa: E402

EXAMPLES = ROOT / "docs" / "examples"
FORMATS = ("fis", "fcl", "fll")
#: Random rule bases per format (fuzzkit writes, the peer evaluates).
N_RANDOM = 24
#: Random rule bases per format that fuzzylite re-writes (the peer writes, fuzzkit reads).
N_RANDOM_CONVERTED = 8
#: Points per random rule base (the examples get ``_peers.N_POINTS``): some random bisector
#: systems with smooth terms take fuzzkit's exact engine ~0.1 s per point.
RANDOM_POINTS = 100
#: Significant digits of the evaluation points (short files; both sides use the same values).
POINT_DIGITS = 7


def _points(rb: RuleBase, name: str, n: int = N_POINTS) -> dict[str, FloatArray]:
    seed = zlib.crc32(name.encode())
    raw = peer_points(rb, seed, n)
    return {k: np.array([float(f"{x:.{POINT_DIGITS}g}") for x in v]) for k, v in raw.items()}


def _fll_for_peers(rb: RuleBase) -> str:
    return fll.dumps(rb).replace(f" {fll.RESOLUTION}", f" {RESOLUTION}")


def _expressible(rb: RuleBase, fmt: str) -> bool:
    if fmt == "fis":
        return not fis.refusals(rb) and not fis.losses(rb)
    if fmt == "fcl":
        return not fcl.losses(rb)
    return True


def _is_sugeno(rb: RuleBase) -> bool:
    return any(v.is_sugeno for v in rb.outputs)


class Writer:
    """Writes inputs and references, and counts them."""

    def __init__(self, tmp: Path) -> None:
        self.tmp = tmp
        self.versions = {
            "fuzzylite": fuzzylite_version(),
            "pyfuzzylite": pyfuzzylite_version(),
        }
        self.written: dict[str, int] = {}

    def input_file(self, name: str, text: str) -> Path:
        path = INPUTS / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
        return path

    def evaluate(
        self,
        peer: str,
        path: Path,
        written_by: str,
        points: dict[str, FloatArray],
        stands_for: Path | None = None,
    ) -> None:
        """``peer``'s outputs for the input ``path`` at ``points``, stored as a reference."""
        fmt = path.suffix[1:]
        if peer == "fuzzylite":
            outputs = fuzzylite_eval(path, fmt, points, self.tmp)
        else:
            outputs = pyfuzzylite_eval(path, points, self.tmp)
        write_reference(
            REFS / peer / f"{path.stem}_{fmt}.json",
            peer=peer,
            peer_version=self.versions[peer],
            input_path=path,
            input_format=fmt,
            written_by=written_by,
            stands_for=stands_for or path,
            points=points,
            outputs=outputs,
        )
        self.written[peer] = self.written.get(peer, 0) + 1


def _iec_in_fuzzylites_spelling(w: Writer, example: Path) -> Path:
    """``example`` (IEC dialect) without comments, ACCU inside DEFUZZIFY and rules in lower
    case: fuzzylite 6 reads no other spelling."""
    text = fcl.dumps(load(example), dialect="iec").replace("  ACCU : MAX;\n", "")
    text = text.replace("  METHOD : COG;", "  METHOD : COG;\n  ACCU : MAX;")
    lines = [
        ln.split(":", 1)[0] + ":" + ln.split(":", 1)[1].lower() if "RULE " in ln else ln
        for ln in text.split("\n")
    ]
    return w.input_file(f"fuzzkit_{example.stem}_for_fuzzylite.fcl", "\n".join(lines))


def _fuzzylite_cases(w: Writer) -> None:
    by_fuzzylite = f"fuzzylite {w.versions['fuzzylite']}"
    by_fuzzkit = f"fuzzkit {fuzzkit_version}"
    for example in sorted(EXAMPLES.iterdir()):
        rb = load(example)
        source, written_by = example, "docs/examples"
        if example.name == "gripper_iec.fcl":
            source = _iec_in_fuzzylites_spelling(w, example)
            written_by = f"{by_fuzzkit} (IEC dialect in fuzzylite's spelling)"
        w.evaluate("fuzzylite", source, written_by, _points(rb, example.name), example)
        for fmt in FORMATS:
            if not _expressible(rb, fmt) or _is_sugeno(rb):
                # fuzzylite writes a Sugeno engine's aggregation as UnboundedSum, which
                # fuzzkit's FLL and FCL readers refuse (the examples are read as written)
                continue
            converted = INPUTS / f"fuzzylite_{example.stem}.{fmt}"
            converted.parent.mkdir(parents=True, exist_ok=True)
            fuzzylite_convert(source, source.suffix[1:], converted)
            if "'discretemf'" in converted.read_text():
                # fuzzylite's own FIS extension for point lists, not MATLAB's: not a FIS file
                print(f"skipped: fuzzylite writes {example.name}'s point lists as discretemf")
                converted.unlink()
                continue
            w.evaluate("fuzzylite", converted, by_fuzzylite, _points(rb, converted.name), example)
    for fmt in FORMATS:
        seeds = [s for s in range(4 * N_RANDOM) if _expressible(random_rulebase(s), fmt)]
        for seed in seeds[:N_RANDOM]:
            rb = random_rulebase(seed)
            path = w.input_file(f"random{seed}.{fmt}", dumps(rb, fmt))
            w.evaluate("fuzzylite", path, by_fuzzkit, _points(rb, path.name, RANDOM_POINTS))
        for seed in seeds[:N_RANDOM_CONVERTED]:
            rb = random_rulebase(seed)
            src = w.tmp / "src.fll"
            src.write_text(fll.dumps(rb))
            converted = INPUTS / f"fuzzylite_random{seed}.{fmt}"
            fuzzylite_convert(src, "fll", converted)
            w.evaluate(
                "fuzzylite", converted, by_fuzzylite, _points(rb, converted.name, RANDOM_POINTS)
            )
    for defuzz, and_, _or, fl_defuzz, fl_and, fl_or in HAND_FLL_CASES:
        path = w.input_file(
            f"{hand_case_name(defuzz, and_)}.fll", hand_fll(fl_defuzz, fl_and, fl_or)
        )
        xy = np.array(hand_points())
        w.evaluate(
            "fuzzylite",
            path,
            "by hand (tests/_sugeno_reference.py)",
            {"x": xy[:, 0], "y": xy[:, 1]},
        )


def _pyfuzzylite_cases(w: Writer) -> None:
    by_fuzzkit = f"fuzzkit {fuzzkit_version}"
    by_pyfuzzylite = f"pyfuzzylite {w.versions['pyfuzzylite']}"
    for example in sorted(EXAMPLES.iterdir()):
        rb = load(example)
        ours = w.input_file(f"fuzzkit_{example.stem}.fll", _fll_for_peers(rb))
        w.evaluate("pyfuzzylite", ours, by_fuzzkit, _points(rb, ours.name), example)
        theirs = w.input_file(f"pyfuzzylite_{example.stem}.fll", pyfuzzylite_export(ours))
        w.evaluate("pyfuzzylite", theirs, by_pyfuzzylite, _points(rb, theirs.name), example)
    for seed in range(N_RANDOM):
        policy = "clamp" if seed % 2 else "extend"
        rb = random_rulebase(seed, out_of_range=policy)
        path = w.input_file(f"random{seed}_{policy}.fll", _fll_for_peers(rb))
        w.evaluate("pyfuzzylite", path, by_fuzzkit, _points(rb, path.name, RANDOM_POINTS))


def main() -> int:
    if FUZZYLITE is None:
        print("the fuzzylite program is missing (`make interop-refs` installs it)", file=sys.stderr)
        return 2
    shutil.rmtree(REFS, ignore_errors=True)
    with tempfile.TemporaryDirectory() as tmp:
        w = Writer(Path(tmp))
        _fuzzylite_cases(w)
        _pyfuzzylite_cases(w)
    size = sum(p.stat().st_size for p in REFS.rglob("*") if p.is_file())
    for peer, n in sorted(w.written.items()):
        print(f"{peer} {w.versions[peer]}: {n} reference files")
    print(f"{REFS.relative_to(ROOT)}: {size / 1e6:.2f} MB")
    return 0


if __name__ == "__main__":
    sys.exit(main())
