"""The estimator's contact gate in the generated controller (issue 42 item 1): a log on which
only the gate stops free-air updates, so that the generated code without its gate is caught."""

from __future__ import annotations

import re

import numpy as np
import pytest
from _codegen_util import needs_cc
from test_adaptation import closed_loop_log, knows_the_loop

from fuzzkit.codegen.target import load_target
from fuzzkit.control.adaptation import CONTACT
from fuzzkit.control.reference import Controller
from fuzzkit.loop.controller_code import generate, open_generated

#: Periods of the free-air part of the log.
FREE_AIR = 400


def gate_log() -> np.ndarray:
    """The step bench's log settled on 5 N/mm, then the tool off the surface with a force that
    swings below the contact gate (a tool that rings, or a cable that pulls): its changes over a
    window pass the excitation threshold and vary, so the dead zone and the spread test let an
    update through, and only the gate stops it."""
    spec = knows_the_loop()
    gate = CONTACT * spec.adaptation.estimator.min_force_n
    forces = closed_loop_log("inner_loop")[0][: int(5.9 / 0.004)]
    t = np.arange(FREE_AIR) * 0.004
    off = np.zeros((FREE_AIR, 3))
    off[:, 2] = 0.8 * gate * np.sin(2.0 * np.pi * 4.0 * t)
    return np.vstack([forces, off])


def reference_run(forces: np.ndarray) -> tuple[np.ndarray, list[float]]:
    ref = Controller(knows_the_loop())
    out, k = [], []
    for f in forces:
        out.append(ref.step(f.tolist())[0])
        k.append(float(ref.hybrid.stiffness_n_mm[2]))
    return np.array(out), k


def without_gate(files: dict[str, str]) -> dict[str, str]:
    """The generated C with its contact gate removed (the estimate updates out of contact)."""
    out, hits = {}, 0
    for path, text in files.items():
        new, n = re.subn(
            r"&& \w+_abs\(f\[i\]\) >= [^\n]*\n"
            r"\s*&& \w+_abs\(c->f_hist\[i\]\[old_f\]\) >= [^)]*(?=\))",
            "",
            text,
        )
        out[path], hits = new, hits + n
    assert hits == 1, "the gate's condition was not found in the generated C"
    return out


def test_the_free_air_swing_would_update_an_ungated_estimate() -> None:
    # the log's own premise, in the reference: every window of the swing is excited
    spec = knows_the_loop()
    est = spec.adaptation.estimator
    f = gate_log()[-FREE_AIR:, 2]
    df = f[est.window_periods :] - f[: -est.window_periods]
    assert np.max(np.abs(f)) < CONTACT * est.min_force_n
    assert np.mean(np.abs(df) >= est.min_force_n) > 0.5


@pytest.mark.parametrize("impl", ["python", pytest.param("c", marks=needs_cc)])
def test_the_generated_estimate_is_frozen_by_the_gate_alone(impl: str) -> None:
    forces = gate_log()
    want, k_ref = reference_run(forces)
    assert len(set(k_ref[-FREE_AIR + 10 :])) == 1  # frozen once off the surface
    rotations = np.tile(np.eye(3).ravel(), (len(forces), 1))
    got, _ = open_generated(knows_the_loop(), impl, "double").run(forces, rotations)
    assert float(np.max(np.abs(got - want))) <= 1e-9


@needs_cc
def test_the_generated_c_without_its_gate_is_caught() -> None:
    forces = gate_log()
    want, _ = reference_run(forces)
    spec = knows_the_loop()
    tg = load_target("c")
    files = without_gate(generate(spec, "c", "double"))
    mutant = tg.open_controller(files, f"{spec.name}_controller", "double")
    rotations = np.tile(np.eye(3).ravel(), (len(forces), 1))
    got, _ = mutant.run(forces, rotations)
    assert float(np.max(np.abs(got - want))) > 1e-6
