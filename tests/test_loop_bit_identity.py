"""The compiled loops' trajectories stay bit-identical (issue 37): a change of the kernels, the
per-period skeleton or the generated C that moves any recorded float by one ulp fails here.

Each case is a short E1 (cut to its contact transient, first contact at about 1.9 s) run
through the loop's entry point as ``fuzzkit simulate`` runs it: the compiled loop with the
spec's generated C controller (double). Its digests are the sha256 of every recorded series
(float64 little-endian, C order; the status bits and contact flags as int64), so one changed bit
anywhere changes them.

How the digests were made: once, from main at 45cc327 (the kernels of this branch unchanged
since), by running this file with ``FUZZKIT_REFRESH_GOLDEN=1`` (it then rewrites
``tests/data/loop_digests.json`` and passes). Regenerate them on purpose only, when a change is
meant to move the trajectories, and say so in the commit with what moved and why. They hold for
one compiler and flags (the generated C is built with the kit's own, no ``-ffast-math``); a
different compiler may contract multiply-adds differently.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import numpy as np
from _codegen_util import needs_cc

from fuzzkit.loop.result import RunResult
from fuzzkit.loop.spec import RunSpec
from fuzzkit.studies.batch import run_spec

DIGESTS = Path(__file__).parent / "data" / "loop_digests.json"
REFRESH = os.environ.get("FUZZKIT_REFRESH_GOLDEN") == "1"
SHORT_S = 2.6

#: (plant, controller, fault): both compiled plants, both controllers, and a fault (spikes:
#: the skeleton's fault path)
CASES = (
    ("arm6", "pi", None),
    ("arm6", "fuzzy-pi", None),
    ("planar", "pi", None),
    ("planar", "fuzzy-pi", None),
    ("arm6", "fuzzy-pi", "spike"),
)
FLOAT_SERIES = (
    "t", "force", "force_sensor", "force_true", "setpoint", "e", "de", "du", "u",
    "tool_position", "nominal_position", "target_position", "joint_angles", "force_normal",
)  # fmt: skip


def case_id(plant: str, controller: str, fault: str | None) -> str:
    return f"E1-{SHORT_S}s-{plant}-{controller}-{fault or 'none'}"


def digests(result: RunResult) -> dict[str, str]:
    """Series name -> sha256 of its bytes."""
    out = {}
    for name in FLOAT_SERIES:
        a = np.ascontiguousarray(getattr(result, name), dtype="<f8")
        out[name] = hashlib.sha256(a.tobytes()).hexdigest()
    for name in ("status", "in_contact"):
        b = np.ascontiguousarray(getattr(result, name), dtype="<i8")
        out[name] = hashlib.sha256(b.tobytes()).hexdigest()
    return out


def _run(plant: str, controller: str, fault: str | None) -> RunResult:
    r = run_spec(RunSpec("E1", controller, plant, seed=1, duration_s=SHORT_S, fault=fault))
    assert r.loop == "compiled" and "generated C controller (double)" in r.controller_impl
    return r


@needs_cc
def test_the_compiled_loops_record_the_committed_trajectories() -> None:
    got = {}
    for c in CASES:
        r = _run(*c)
        assert r.in_contact.any()  # the digests cover the contact transient, not only the approach
        got[case_id(*c)] = digests(r)
    if REFRESH:
        DIGESTS.write_text(json.dumps(got, indent=1, sort_keys=True) + "\n", encoding="utf-8")
    want = json.loads(DIGESTS.read_text(encoding="utf-8"))
    assert set(want) == set(got)
    moved = {case: [s for s in want[case] if want[case][s] != got[case].get(s)] for case in want}
    assert not any(moved.values()), f"series that moved (not bit-identical): {moved}"


@needs_cc
def test_the_digests_see_one_ulp() -> None:
    # the check can fail: one ulp in one sample of one series changes its digest
    r = _run("planar", "pi", None)
    before = digests(r)
    k = len(r.t) // 2
    r.u[k, 2] = np.nextafter(r.u[k, 2], np.inf)
    after = digests(r)
    assert [s for s in before if before[s] != after[s]] == ["u"]
