"""Run-time parameters of the generated controller (issue 28 item 1): ``NAME_controller_init``
loads the spec's values, ``NAME_controller_set_params`` (C) and ``Controller.set_params``
(Python) change set points, gains and correction limits without recompiling; the compiled
controllers are cached on disk by their code.

The reference for "set_params(values) behaves as the spec with those values" is the controller
generated from that other spec, run on the same samples: equal bit for bit in double.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from _codegen_util import needs_cc

from fuzzkit.control.spec import ControllerSpec, Limits
from fuzzkit.control.spec_reader import load_spec
from fuzzkit.loop.compiled.generated_controller import code_spec, params_of
from fuzzkit.loop.controller_code import open_generated

ROOT = Path(__file__).resolve().parent.parent
SPECS = {
    "fuzzy": ROOT / "docs" / "examples" / "controller.yaml",
    "pi": ROOT / "docs" / "examples" / "controller_pi.yaml",
    "renamed": ROOT / "tests" / "data" / "user" / "spec_renamed.yaml",
}


def _other(spec: ControllerSpec) -> ControllerSpec:
    """``spec`` with every run-time parameter changed (and the step limit tight enough to act)."""
    axes = tuple(
        dataclasses.replace(
            a,
            setpoint_n=a.setpoint_n + 2.5,
            kp=a.kp * 1.7,
            ki=a.ki * 0.6,
            kx=None if a.kx is None else a.kx * 1.3,
        )
        for a in spec.axes
    )
    return dataclasses.replace(spec, axes=axes, limits=Limits(0.004, 2e-5))


def _samples(n: int = 600) -> np.ndarray:
    """Forces that engage, press, spike, go missing and saturate the limits."""
    rng = np.random.default_rng(7)
    t = np.arange(n) * 0.004
    f = np.zeros((n, 3))
    f[:, 2] = np.clip((t - 0.2) * 40.0, 0.0, 14.0) + rng.normal(0.0, 0.1, n)
    f[:, 0] = rng.normal(0.0, 0.3, n)
    f[300, :] += 15.0  # a spike the gate rejects
    f[400:405, :] = np.nan  # a dropout
    return f


@needs_cc
@pytest.mark.parametrize("target", ["c", "python"])
@pytest.mark.parametrize("name", sorted(SPECS))
def test_set_params_runs_as_the_spec_with_those_values(name: str, target: str) -> None:
    spec = load_spec(SPECS[name])
    other = _other(spec)
    rot = np.tile(np.eye(3).reshape(9), (600, 1))
    want, want_status = open_generated(other, target, "double").run(_samples(), rot)
    ctl = open_generated(spec, target, "double")
    ctl.set_params(params_of(other))
    got, status = ctl.run(_samples(), rot)
    np.testing.assert_array_equal(got, want)
    np.testing.assert_array_equal(status, want_status)
    # and the spec's own values differ, so the parameters really were used
    own, _ = open_generated(spec, target, "double").run(_samples(), rot)
    assert float(np.max(np.abs(own - want))) > 1e-5


@needs_cc
@pytest.mark.parametrize("target", ["c", "python"])
def test_one_code_runs_every_gain_set(target: str) -> None:
    spec = load_spec(SPECS["fuzzy"])
    other = _other(spec)
    assert code_spec(spec) == code_spec(other)  # what a tune compiles once
    ctl = open_generated(code_spec(spec), target, "double")
    ctl.set_params(params_of(other))
    rot = np.tile(np.eye(3).reshape(9), (600, 1))
    want, _ = open_generated(other, target, "double").run(_samples(), rot)
    got, _ = ctl.run(_samples(), rot)
    np.testing.assert_array_equal(got, want)


@needs_cc
@pytest.mark.parametrize("target", ["c", "python"])
@pytest.mark.parametrize(
    ("index", "value"),
    [
        (2, 25.0),  # z set point at the safety limit
        (2, math.nan),
        (5, -0.1),  # z kp < 0
        (8, 0.0),  # a fuzzy-PI's ki must be > 0
        (11, math.inf),  # z kx
        (12, 0.0),  # correction_m
        (13, -1e-3),  # step_m
    ],
)
def test_set_params_refuses_what_the_spec_reader_refuses(
    target: str, index: int, value: float
) -> None:
    spec = load_spec(SPECS["fuzzy"])
    ctl = open_generated(spec, target, "double")
    bad = list(params_of(spec))
    bad[index] = value
    rot = np.tile(np.eye(3).reshape(9), (600, 1))
    want, _ = open_generated(spec, target, "double").run(_samples(), rot)
    with pytest.raises(ValueError, match="refused"):
        ctl.set_params(bad)
    got, _ = ctl.run(_samples(), rot)
    np.testing.assert_array_equal(got, want)  # nothing changed


@needs_cc
def test_reset_keeps_the_parameters() -> None:
    spec = load_spec(SPECS["pi"])
    other = _other(spec)
    rot = np.tile(np.eye(3).reshape(9), (600, 1))
    want, _ = open_generated(other, "c", "double").run(_samples(), rot)
    ctl = open_generated(spec, "c", "double")
    ctl.set_params(params_of(other))
    ctl.run(_samples(), rot)
    ctl.reset()
    got, _ = ctl.run(_samples(), rot)
    np.testing.assert_array_equal(got, want)


@needs_cc
def test_compiled_controllers_are_cached_on_disk(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from fuzzkit.codegen import toolchain
    from fuzzkit.codegen.backends.c.run import CompiledController, harness_source
    from fuzzkit.loop.controller_code import generate

    monkeypatch.setenv("FUZZKIT_CACHE_DIR", str(tmp_path))
    calls: list[list[str]] = []
    real = toolchain.run_compiler

    def counting(argv: list[str], *args: object, **kw: object) -> object:
        calls.append(list(argv))
        return real(argv, *args, **kw)  # type: ignore[arg-type]

    monkeypatch.setattr(toolchain, "run_compiler", counting)
    spec = load_spec(SPECS["pi"])
    files = generate(spec, "c", "double")
    first = CompiledController(files, "e1_pi_controller", "double")
    assert len(calls) == 1
    (cached,) = (tmp_path / "controllers").glob("*.so")
    second = CompiledController(files, "e1_pi_controller", "double")
    assert len(calls) == 1  # loaded, not compiled
    assert first.step([0.0, 0.0, 5.0]) == second.step([0.0, 0.0, 5.0])
    # other code is another library; a damaged cache file is compiled again, never trusted
    changed = {k: v.replace("10.0", "11.0") for k, v in files.items()}
    harness = {"fuzzkit_controller_harness.c": harness_source("e1_pi_controller", "double")}
    cc = toolchain.find_compiler()
    assert cc is not None
    path = toolchain.library_cache_path(
        {**changed, **harness}, "e1_pi_controller", cc, (*toolchain.STRICT_FLAGS, "-O2"), ("-lm",)
    )
    path.write_bytes(b"not a library")
    third = CompiledController(changed, "e1_pi_controller", "double")
    assert len(calls) == 2
    rot = np.tile(np.eye(3).reshape(9), (600, 1))
    first.reset()
    assert not np.array_equal(third.run(_samples(), rot)[0], first.run(_samples(), rot)[0])
    assert path.stat().st_size > 1000 and cached.is_file()
