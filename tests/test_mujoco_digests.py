"""Short MuJoCo runs (rigid and elastic arm, the compiled loop with the servo callback and the
Python loop with the Python ramp) give the trajectories recorded in
``tests/data/mujoco_digests.json`` bit for bit: every recorded series' SHA-256
(``tests/_mujoco_digests.py`` says how the file was made). A change that moves any double of
any series fails here, and must be explained (and the docs' MuJoCo figures re-measured)."""

from __future__ import annotations

import json
from collections.abc import Iterator

import mujoco
import pytest
from _codegen_util import needs_cc
from _mujoco_digests import FILE, RUNS, DigestRun, digests, execute

from fuzzkit.plants.mujoco_servo import ServoCallback

pytestmark = needs_cc  # the generated C controller, and the callback in the compiled loop

RECORDED = json.loads(FILE.read_text(encoding="utf-8"))


@pytest.fixture(autouse=True)
def _no_callback_after() -> Iterator[None]:
    yield
    ServoCallback.uninstall()


@pytest.mark.skipif(
    RECORDED["versions"]["mujoco"] != mujoco.__version__,
    reason=f"digests recorded with MuJoCo {RECORDED['versions']['mujoco']}, whose "
    f"trajectories another release ({mujoco.__version__}) need not repeat",
)
@pytest.mark.parametrize("run_", RUNS, ids=[r.key for r in RUNS])
def test_the_mujoco_runs_repeat_the_recorded_trajectories_bit_for_bit(run_: DigestRun) -> None:
    r = execute(run_)
    assert r.engaged_time_s is not None  # the digests cover contact
    expected = RECORDED["runs"][run_.key]
    got = digests(r)
    changed = sorted(k for k in expected if got.get(k) != expected[k])
    assert not changed, f"series that changed: {changed}"
    assert sorted(got) == sorted(expected)
