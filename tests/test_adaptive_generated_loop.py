"""Adaptive specs run their generated controller (issue 37 item 2, issue 42): on every plant the
loop executes the spec's generated code (the double C in the compiled loop, or the generated
Python in the Python loop) and records the code's own gain factor and stiffness estimate per
period, read through ``NAME_controller_adaptation`` (C) or ``Controller.adaptation`` (Python).

The reference controller is the independent check: the run's consumed samples are stepped
through it, and its corrections, status bits, gain factor and estimate must follow the run's
period for period. ``fuzzkit simulate --csv`` then ``fuzzkit replay`` reproduces a run to 0 m
with identical status bits.
"""

from __future__ import annotations

import functools
import json
from pathlib import Path

import numpy as np
import pytest
from _codegen_util import needs_cc
from _pairwise import matrix_params
from _replay_logs import read_out

from fuzzkit.analysis.regulation import regulation_experiment
from fuzzkit.cli import main
from fuzzkit.control import status as st
from fuzzkit.control.reference import Controller
from fuzzkit.control.spec import ControllerSpec
from fuzzkit.control.spec_reader import load_spec
from fuzzkit.loop.result import RunResult
from fuzzkit.loop.run import run_loop
from fuzzkit.loop.spec import RunSpec
from fuzzkit.studies.experiments import with_spec

EXAMPLES = Path(__file__).resolve().parent.parent / "docs" / "examples"
#: Each adaptive controller kind, as shipped: a banded stiffness schedule on a fuzzy-PI, the
#: 1/k schedule on the same, a self-tuning PI.
KINDS = {
    "banded": EXAMPLES / "controller_adaptive.yaml",
    "inverse": EXAMPLES / "controller_inverse.yaml",
    "self-tuning": EXAMPLES / "controller_selftuning.yaml",
}
PLANTS = ("planar", "arm6", "mujoco")
#: ``auto``: the generated C (the compiled loop on every plant here); ``python``: the
#: generated Python module in the Python loop.
IMPLS = ("auto", "python")
#: The regulation task's contact stiffness (N/mm) and the run's length (s): the approach, the
#: contact and about 1 s of holding 12 N.
K_N_MM = 50.0
DURATION_S = 2.5


@functools.cache
def spec_of(kind: str) -> ControllerSpec:
    return load_spec(KINDS[kind])


def run(kind: str, plant: str, impl: str, seed: int) -> RunResult:
    cs = spec_of(kind)
    exp = with_spec(regulation_experiment(K_N_MM * 1e3, 12.0), cs)
    spec = RunSpec(
        exp.name,
        controller=cs.kind,
        plant=plant,
        seed=seed,
        duration_s=DURATION_S,
        controller_impl=impl,
        fault="spike",
    )
    return run_loop(spec, exp, plant)


def reference_replay(cs: ControllerSpec, res: RunResult) -> dict[str, np.ndarray]:
    """The reference controller stepped on the run's consumed samples, from reset: its
    correction, status, gain factor and stiffness estimate per period."""
    ref = Controller(cs)
    rot = res.rotation if res.rotation is not None else np.tile(np.eye(3).ravel(), (len(res.t), 1))
    u, status, factor, k = [], [], [], []
    for f, r in zip(res.force, rot, strict=True):
        out, bits = ref.step(f.tolist(), r.tolist())
        u.append(out)
        status.append(bits)
        factor.append(ref.hybrid.gain_scale.copy())
        k.append(ref.hybrid.stiffness_n_mm.copy())
    return {"u": np.array(u), "status": np.array(status), "factor": np.array(factor),
            "k": np.array(k)}  # fmt: skip


@pytest.mark.parametrize(
    ("kind", "plant", "impl", "seed"),
    matrix_params([sorted(KINDS), PLANTS, IMPLS], cover_seeds=(0,), verify_seeds=(1,)),
)
@needs_cc
def test_an_adaptive_spec_runs_its_generated_controller_as_the_reference_would(
    kind: str, plant: str, impl: str, seed: int
) -> None:
    res = run(kind, plant, impl, seed)
    if impl == "auto":
        assert res.loop == "compiled", res.loop
        assert res.controller_impl.startswith("generated C controller (double)")
    else:
        assert res.loop == "python", res.loop
        assert res.controller_impl.startswith("generated Python controller")
    assert res.engaged_time_s is not None  # in contact (a trip, too, must follow the reference)
    assert res.gain_scale is not None and res.stiffness_n_mm is not None
    want = reference_replay(spec_of(kind), res)
    np.testing.assert_array_equal(res.status, want["status"])
    assert float(np.max(np.abs(res.u - want["u"]))) <= 1e-9
    np.testing.assert_allclose(res.gain_scale, want["factor"], rtol=1e-9, atol=0.0)
    np.testing.assert_allclose(res.stiffness_n_mm, want["k"], rtol=1e-9, atol=0.0)
    z = res.gain_scale[:, 2]
    if kind == "banded":
        assert np.isnan(res.stiffness_n_mm[:, :2]).all()  # x and y are motion-only axes
        assert np.count_nonzero(np.diff(res.stiffness_n_mm[:, 2])) > 0  # it estimated
        assert set(np.unique(z)) <= {0.5, 0.2, 0.05, 0.02}
    elif kind == "inverse":
        k = res.stiffness_n_mm[:, 2]
        trusted = (res.status & st.UNTRUSTED) == 0
        # min(1, 15 / k) of the estimate once trusted, of k_max (2000 N/mm) before
        np.testing.assert_allclose(z[trusted], np.minimum(1.0, 15.0 / k[trusted]), rtol=1e-12)
        assert (z[~trusted] == 15.0 / 2000.0).all() and trusted.any()
    else:
        assert np.isnan(res.stiffness_n_mm).all()
        assert z.min() >= 0.2 and z.max() <= 1.0 and np.ptp(z) > 0.1  # it tuned itself
    assert (res.gain_scale[:, :2] == 1.0).all()


@needs_cc
@pytest.mark.parametrize("kind", sorted(KINDS))
def test_simulate_csv_then_replay_reproduces_an_adaptive_run(
    kind: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    csv, out = tmp_path / "run.csv", tmp_path / "u.csv"
    args = ["simulate", "E1", "--plant", "arm6", "--spec", str(KINDS[kind]), "--stiffness", "50"]
    assert main([*args, "--csv", str(csv), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["loop"] == "compiled"
    assert data["controller_impl"].startswith("generated C controller (double)")
    assert main(["replay", str(KINDS[kind]), "--forces", str(csv), "--out", str(out),
                 "--impl", "c"]) == 0  # fmt: skip
    assert "largest difference from the run's corrections (u<a>_m): 0 m" in capsys.readouterr().out
    header, rows = read_out(out)
    assert float(np.max(np.abs(rows[:, header.index("uz")]))) > 1e-4  # the controller corrected


@needs_cc
def test_the_c_accessor_reports_what_the_python_accessor_reports() -> None:
    """Both generated targets' adaptation accessors on one hostile log, against the
    reference's (before the first step too)."""
    from fuzzkit.loop.controller_code import open_generated

    rng = np.random.default_rng(3)
    n = 600
    forces = np.zeros((n, 3))
    forces[:, 2] = np.clip(np.cumsum(rng.normal(0.05, 0.4, n)), 0.0, 20.0)
    forces[rng.integers(0, n, 20), 2] = np.nan
    for kind in KINDS:
        cs = spec_of(kind)
        ref = Controller(cs)
        ctls = [open_generated(cs, impl, "double") for impl in ("c", "python")]
        for k in range(-1, n):
            if k >= 0:
                f = forces[k].tolist()
                ref.step(f)
                for ctl in ctls:
                    ctl.step(f)
            want = (list(ref.hybrid.gain_scale), list(ref.hybrid.stiffness_n_mm))
            for ctl in ctls:
                factor, stiffness, band = ctl.adaptation()
                np.testing.assert_allclose(factor, want[0], rtol=1e-12)
                np.testing.assert_allclose(stiffness, want[1], rtol=1e-12)
                assert band[:2] == [-1, -1]
                assert (band[2] >= 0) == (kind == "banded")  # the 1/k schedule has none
