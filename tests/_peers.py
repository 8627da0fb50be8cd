"""Independent implementations the interop tests compare fuzzkit with, run in subprocesses.

* fuzzylite 6, the C++ command-line program of Debian's ``fuzzylite`` package: imports FIS,
  FCL and FLL, exports them, and evaluates an engine on an FLD table of inputs.
* pyfuzzylite 8 in its own environment (``make interop`` builds ``.venv-interop``; it pins
  numpy<2, so it never enters the project's ``.venv``): reads and writes FLL.

fuzzylite integrates centroids and bisectors numerically; :func:`fuzzylite_eval` evaluates at
:data:`RESOLUTION` steps (by rewriting the resolution in fuzzylite's own FLL export of the
engine) so that the comparison measures the formats, not fuzzylite's quadrature.
"""

from __future__ import annotations

import json
import math
import os
import re
import shutil
import subprocess
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

import numpy as np
import numpy.typing as npt
import pytest
from _random_rulebases import MAXIMA

from fuzzkit.fuzzy.model import RuleBase

ROOT = Path(__file__).resolve().parent.parent
FUZZYLITE = shutil.which("fuzzylite")
INTEROP_PYTHON = Path(os.environ.get("FUZZKIT_INTEROP_PYTHON", ROOT / ".venv-interop/bin/python"))
PYFUZZYLITE_SCRIPT = ROOT / "tests" / "peers" / "pyfuzzylite_eval.py"
RESOLUTION = 10000
#: Points per comparison: random, inside and up to 10 % beyond every input's range.
N_POINTS = 200

FloatArray = npt.NDArray[np.float64]


def peer_points(rb: RuleBase, seed: int, n: int = N_POINTS) -> dict[str, FloatArray]:
    """``n`` random points per input of ``rb``, up to 10 % beyond its range (where clamping or
    its absence matters)."""
    rng = np.random.default_rng(seed)
    return {
        v.name: rng.uniform(v.low - 0.1 * (v.high - v.low), v.high + 0.1 * (v.high - v.low), n)
        for v in rb.inputs
    }


def largest_difference(
    rb: RuleBase, ours: dict[str, FloatArray], theirs: dict[str, FloatArray]
) -> float:
    """Check a peer's outputs ``theirs`` against fuzzkit's ``ours``; the largest difference (as a
    fraction of the output range) over the points that must agree. Tolerances:

    * centroid: 1e-6 (the peers integrate on RESOLUTION steps; fuzzkit is exact);
    * bisector and the maxima: 2 / RESOLUTION (one integration step). fuzzylite 6 takes values
      within 1e-6 of its running maximum as maximal and samples at step midpoints, so where
      two maxima are that close (a near tie) it may pick the other one: at most 3 % of the
      points may differ for the maxima defuzzifiers, and the rest must agree;
    * Sugeno (no integration on either side): 1e-9 of the range.

    NaN (no rule fired, a NaN default) must be NaN on both sides.
    """
    worst = 0.0
    for var in rb.outputs:
        width = var.high - var.low
        a, b = np.asarray(ours[var.name]), np.asarray(theirs[var.name])
        if a.shape != b.shape:
            raise AssertionError(f"{var.name}: {a.shape} values against the peer's {b.shape}")
        one_sided = np.isnan(a) != np.isnan(b)
        if np.any(one_sided):
            raise AssertionError(f"{var.name}: NaN on one side only at {np.sum(one_sided)} points")
        both = ~np.isnan(a)
        diff = np.abs(a[both] - b[both]) / width
        if var.is_sugeno:
            tol, share = 1e-9, 1.0
        elif rb.defuzzifier == "centroid":
            tol, share = 1e-6, 1.0
        else:
            tol = 2.0 / RESOLUTION
            share = 0.97 if rb.defuzzifier in MAXIMA else 1.0
        agree = diff <= tol
        if agree.size and agree.mean() < share:
            raise AssertionError(
                f"{var.name} ({rb.defuzzifier}): {np.sum(~agree)} of {diff.size} points differ "
                f"by more than {tol:g} of the range, up to {diff.max():.3g}"
            )
        worst = max(worst, float(np.max(diff[agree], initial=0.0)))
    return worst


def _has_pyfuzzylite() -> bool:
    if not INTEROP_PYTHON.exists():
        return False
    done = subprocess.run(
        [str(INTEROP_PYTHON), "-c", "import fuzzylite"], capture_output=True, check=False
    )
    return done.returncode == 0


_skip_fuzzylite = pytest.mark.skipif(
    FUZZYLITE is None,
    reason="the fuzzylite program is missing (apt-get install fuzzylite, or `make interop`)",
)
_skip_pyfuzzylite = pytest.mark.skipif(
    not _has_pyfuzzylite(),
    reason=f"pyfuzzylite is missing in {INTEROP_PYTHON} (`make interop` builds .venv-interop)",
)
F = TypeVar("F", bound=Callable[..., object])


def needs_fuzzylite(test: F) -> F:
    """Mark ``test`` ``needs_fuzzylite`` (``-m needs_fuzzylite``); skip it without the program."""
    return pytest.mark.needs_fuzzylite(_skip_fuzzylite(test))  # type: ignore[no-any-return]


def needs_pyfuzzylite(test: F) -> F:
    """Mark ``test`` ``needs_pyfuzzylite``; skip it without .venv-interop."""
    return pytest.mark.needs_pyfuzzylite(_skip_pyfuzzylite(test))  # type: ignore[no-any-return]


def _run(args: list[str]) -> None:
    done = subprocess.run(args, capture_output=True, text=True, check=False, timeout=120)
    if done.returncode != 0 or "error]" in done.stdout + done.stderr:
        raise AssertionError(f"{' '.join(args)} failed:\n{done.stdout}\n{done.stderr}")


def fuzzylite_convert(src: Path, src_fmt: str, dst: Path) -> Path:
    """``src`` re-written by fuzzylite in the format of ``dst``'s extension."""
    assert FUZZYLITE is not None
    _run([FUZZYLITE, "-i", str(src), "-if", src_fmt, "-o", str(dst), "-of", dst.suffix[1:]])
    return dst


def fuzzylite_eval(
    src: Path, src_fmt: str, points: dict[str, FloatArray], tmp: Path
) -> dict[str, FloatArray]:
    """fuzzylite's outputs for ``src`` (imported by fuzzylite as ``src_fmt``) at ``points``."""
    assert FUZZYLITE is not None
    fll = fuzzylite_convert(src, src_fmt, tmp / "engine_by_fuzzylite.fll")
    text = re.sub(
        r"(Centroid|Bisector|MeanOfMaximum|SmallestOfMaximum|LargestOfMaximum) \d+",
        rf"\1 {RESOLUTION}",
        fll.read_text(),
    )
    fll.write_text(text)
    names = list(points)
    rows = np.column_stack([np.asarray(points[n], dtype=float) for n in names])
    fld = tmp / "inputs.fld"
    fld.write_text(
        " ".join(names) + "\n" + "\n".join(" ".join(repr(float(x)) for x in r) for r in rows) + "\n"
    )
    out = tmp / "outputs.fld"
    _run(
        [
            FUZZYLITE,
            "-i",
            str(fll),
            "-if",
            "fll",
            "-o",
            str(out),
            "-of",
            "fld",
            "-d",
            str(fld),
            "-decimals",
            "12",
        ]
    )
    lines = out.read_text().split("\n")
    header = lines[0].split()
    table = np.array([[float(x) for x in ln.split()] for ln in lines[1:] if ln.strip()])
    return {h: table[:, i] for i, h in enumerate(header) if h not in names}


def pyfuzzylite_eval(fll: Path, points: dict[str, FloatArray], tmp: Path) -> dict[str, FloatArray]:
    """pyfuzzylite's outputs for the FLL file ``fll`` at ``points``."""
    data = tmp / "points.json"
    data.write_text(json.dumps({k: [float(x) for x in v] for k, v in points.items()}))
    done = subprocess.run(
        [str(INTEROP_PYTHON), str(PYFUZZYLITE_SCRIPT), "eval", str(fll), str(data)],
        capture_output=True,
        text=True,
        check=True,
        timeout=300,
    )
    raw = json.loads(done.stdout)
    return {k: np.array([math.nan if x is None else x for x in v]) for k, v in raw.items()}


def pyfuzzylite_version() -> str:
    """The version pyfuzzylite reports (``fuzzylite.__version__``)."""
    done = subprocess.run(
        [str(INTEROP_PYTHON), str(PYFUZZYLITE_SCRIPT), "version"],
        capture_output=True,
        text=True,
        check=True,
        timeout=120,
    )
    return done.stdout.strip()


def fuzzylite_version() -> str:
    """The version the fuzzylite program prints in its banner (``version: 6.0``)."""
    assert FUZZYLITE is not None
    done = subprocess.run([FUZZYLITE, "--version"], capture_output=True, text=True, check=False)
    found = re.search(r"version:\s*(\S+)", done.stdout + done.stderr)
    if found is None:
        raise AssertionError(f"no version in the fuzzylite banner:\n{done.stdout}{done.stderr}")
    return found.group(1)


def pyfuzzylite_export(fll: Path) -> str:
    """The FLL text pyfuzzylite writes for the engine it reads from ``fll``."""
    done = subprocess.run(
        [str(INTEROP_PYTHON), str(PYFUZZYLITE_SCRIPT), "export", str(fll)],
        capture_output=True,
        text=True,
        check=True,
        timeout=120,
    )
    return done.stdout
