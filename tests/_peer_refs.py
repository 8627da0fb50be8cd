"""Committed outputs of the peers (fuzzylite 6, pyfuzzylite 8), so ``make test`` compares with
them without either installed.

One JSON file per (peer, input file) under ``tests/peers/refs/<peer>/``:

* ``peer``, ``peer_version``: who computed the outputs (``fuzzylite --version``,
  ``fuzzylite.__version__``);
* ``input``: the file the peer read, relative to the repository (a file of ``docs/examples/``
  or one under ``tests/peers/refs/inputs/``), its ``input_format`` and ``input_sha256``;
  ``written_by`` says who wrote that file (the example's author, fuzzkit's writer, a peer);
  ``stands_for``: the file whose system it holds (an example it was converted from, or the
  input itself);
* ``points``: the evaluation points per input; ``outputs``: the peer's value per output at
  each point (``null`` for NaN: no rule fired and the default is NaN).

``make interop-refs`` writes them (tests/peers/make_refs.py); tests/test_peer_refs.py
compares fuzzkit with them.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

ROOT = Path(__file__).resolve().parent.parent
REFS = ROOT / "tests" / "peers" / "refs"
#: Input files the peers read that are not in docs/examples (written by fuzzkit or a peer).
INPUTS = REFS / "inputs"
PEERS = ("fuzzylite", "pyfuzzylite")

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class Reference:
    """One committed peer evaluation (module docstring: the fields)."""

    path: Path
    peer: str
    peer_version: str
    input: Path
    input_format: str
    input_sha256: str
    written_by: str
    stands_for: Path
    points: dict[str, FloatArray]
    outputs: dict[str, FloatArray]


def sha256_of(path: Path) -> str:
    """The hex SHA-256 of ``path``'s bytes."""
    return hashlib.sha256(path.read_bytes()).hexdigest()


def reference_files() -> list[Path]:
    """Every committed type-1 reference file, sorted (pyit2fls's interval type-2 references
    have their own format and test, tests/test_type2_peers.py)."""
    return sorted(p for p in REFS.glob("*/*.json") if p.parent.name != "pyit2fls")


def _array(values: list[float | None]) -> FloatArray:
    return np.array([math.nan if v is None else v for v in values], dtype=float)


def read_reference(path: Path) -> Reference:
    """The reference stored in ``path``."""
    doc = json.loads(path.read_text(encoding="utf-8"))
    return Reference(
        path=path,
        peer=doc["peer"],
        peer_version=doc["peer_version"],
        input=ROOT / doc["input"],
        input_format=doc["input_format"],
        input_sha256=doc["input_sha256"],
        written_by=doc["written_by"],
        stands_for=ROOT / doc["stands_for"],
        points={k: _array(v) for k, v in doc["points"].items()},
        outputs={k: _array(v) for k, v in doc["outputs"].items()},
    )


def write_reference(
    path: Path,
    *,
    peer: str,
    peer_version: str,
    input_path: Path,
    input_format: str,
    written_by: str,
    stands_for: Path,
    points: dict[str, FloatArray],
    outputs: dict[str, FloatArray],
) -> None:
    """Store a peer's ``outputs`` for ``input_path`` at ``points`` (with the input's hash)."""

    def values(a: FloatArray) -> list[float | None]:
        return [None if math.isnan(float(x)) else float(x) for x in a]

    doc = {
        "peer": peer,
        "peer_version": peer_version,
        "input": input_path.relative_to(ROOT).as_posix(),
        "input_format": input_format,
        "input_sha256": sha256_of(input_path),
        "written_by": written_by,
        "stands_for": stands_for.relative_to(ROOT).as_posix(),
        "points": {k: values(v) for k, v in points.items()},
        "outputs": {k: values(v) for k, v in outputs.items()},
    }
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
