"""fuzzkit against the committed outputs of fuzzylite 6 and pyfuzzylite 8 (no peer installed).

Each reference under tests/peers/refs/ holds a peer's outputs for one input file at recorded
points (tests/_peer_refs.py); fuzzkit reads the same file and must agree with the tolerances
of ``_peers.largest_difference``. ``make interop-refs`` regenerates them with the peers;
``make interop`` runs the live comparisons (tests/test_interop_peers.py).
"""

from __future__ import annotations

import dataclasses
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from _pairwise import verify
from _peer_refs import INPUTS, PEERS, ROOT, Reference, read_reference, reference_files, sha256_of
from _peers import MAXIMA, largest_difference

from fuzzkit.formats.registry import load
from fuzzkit.fuzzy.inference import evaluate

#: The example rule bases in foreign formats (docs/examples also holds controller specs and
#: scenarios, which no peer reads).
EXAMPLES = sorted(
    p for p in (ROOT / "docs" / "examples").iterdir() if p.suffix in {".fis", ".fcl", ".fll"}
)
REFERENCES = [read_reference(p) for p in reference_files()]
#: Random rule bases the references must hold at least, per peer and format.
MIN_RANDOM = {
    ("fuzzylite", "fis"): 24,
    ("fuzzylite", "fcl"): 24,
    ("fuzzylite", "fll"): 24,
    ("pyfuzzylite", "fll"): 24,
}


def _id(ref: Reference) -> str:
    return f"{ref.peer}/{ref.path.stem}"


def _stale(ref: Reference) -> bool:
    return sha256_of(ref.input) != ref.input_sha256


#: Points of each reference ``make test`` compares (``make verify``: all of them). A smooth
#: output under the bisector costs the exact engine tens of ms a point, and the random
#: families hold 100 points; every reference file and output is still read and compared.
COVER_POINTS = 25


def _check(ref: Reference, points: int | None = None) -> float:
    """fuzzkit against ``ref`` at its first ``points`` points (all when None, and always all
    for the maxima defuzzifiers, whose tolerance is a share of every point: a near tie may
    fall among the first few)."""
    rb = load(ref.input)
    assert sorted(ref.outputs) == sorted(v.name for v in rb.outputs)
    if points is None or rb.defuzzifier in MAXIMA:
        return largest_difference(rb, evaluate(rb, ref.points), ref.outputs)
    at = {name: values[:points] for name, values in ref.points.items()}
    theirs = {name: values[:points] for name, values in ref.outputs.items()}
    return largest_difference(rb, evaluate(rb, at), theirs)


@pytest.mark.parametrize(
    "ref, points",
    [pytest.param(r, COVER_POINTS, id=f"cover-{_id(r)}") for r in REFERENCES]
    + [pytest.param(r, None, marks=verify, id=f"full-{_id(r)}") for r in REFERENCES],
)
def test_fuzzkit_reads_and_evaluates_as_the_peer_did(ref: Reference, points: int | None) -> None:
    _check(ref, points)


def test_the_covering_points_are_the_first_of_every_reference() -> None:
    # the short comparison is a part of the full one, on every file and output
    ref = next(r for r in REFERENCES if len(next(iter(r.points.values()))) > COVER_POINTS)
    rb = load(ref.input)
    if rb.defuzzifier in MAXIMA:
        pytest.skip("a maxima reference is always compared whole")
    moved = {k: v.copy() for k, v in ref.outputs.items()}
    name = sorted(moved)[0]
    var = next(v for v in rb.outputs if v.name == name)
    past = COVER_POINTS + int(np.flatnonzero(~np.isnan(moved[name][COVER_POINTS:]))[0])
    moved[name][past] += 0.5 * (var.high - var.low)
    _check(dataclasses.replace(ref, outputs=moved), COVER_POINTS)  # past the cover: not seen
    with pytest.raises(AssertionError):
        _check(dataclasses.replace(ref, outputs=moved))


def test_no_reference_is_stale() -> None:
    stale = [f"{_id(r)} ({r.input.relative_to(ROOT)})" for r in REFERENCES if _stale(r)]
    assert not stale, "inputs changed since the peers ran; `make interop-refs`:\n" + "\n".join(
        stale
    )


def test_a_changed_input_is_reported_stale(tmp_path: Path) -> None:
    ref = next(r for r in REFERENCES if r.input.suffix == ".fis")
    copy = tmp_path / ref.input.name
    shutil.copy(ref.input, copy)
    assert not _stale(dataclasses.replace(ref, input=copy))
    copy.write_text(copy.read_text().replace("0", "1", 1))
    assert _stale(dataclasses.replace(ref, input=copy))


def test_a_changed_output_is_caught() -> None:
    # one output moved by 1e-4 of its range, ten times the centroid tolerance
    ref = next(r for r in REFERENCES if load(r.input).defuzzifier == "centroid")
    name = sorted(ref.outputs)[0]
    var = next(v for v in load(ref.input).outputs if v.name == name)
    moved = ref.outputs[name].copy()
    moved[np.flatnonzero(~np.isnan(moved))[0]] += 1e-4 * (var.high - var.low)
    with pytest.raises(AssertionError, match="points differ"):
        _check(dataclasses.replace(ref, outputs={**ref.outputs, name: moved}))


def test_references_name_their_peer_version_and_points() -> None:
    for ref in REFERENCES:
        assert ref.peer in PEERS and ref.path.parent.name == ref.peer
        assert re.fullmatch(r"\d+\.\d+(\.\d+)?", ref.peer_version), ref.peer_version
        assert ref.input.suffix == f".{ref.input_format}"
        sizes = {a.size for a in [*ref.points.values(), *ref.outputs.values()]}
        assert len(sizes) == 1 and sizes.pop() >= 100, _id(ref)


@pytest.mark.parametrize("peer", PEERS)
def test_every_example_has_references_from_both_peers(peer: str) -> None:
    covered = {r.stands_for for r in REFERENCES if r.peer == peer}
    assert set(EXAMPLES) <= covered, sorted(p.name for p in set(EXAMPLES) - covered)


def test_a_few_dozen_random_rule_bases_per_peer_and_format() -> None:
    counts: dict[tuple[str, str], int] = {}
    for ref in REFERENCES:
        if ref.input.parent == INPUTS and ref.input.name.startswith("random"):
            key = (ref.peer, ref.input_format)
            counts[key] = counts.get(key, 0) + 1
    for key, least in MIN_RANDOM.items():
        assert counts.get(key, 0) >= least, (key, counts)
