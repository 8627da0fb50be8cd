"""Latency: sensor and command delays shift the loop's signals by whole periods, and too much
delay destabilises aggressive gains."""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pytest

from fuzzkit.control.controllers import Surface
from fuzzkit.errors import ConfigError
from fuzzkit.loop.python_loop import load_surface, run
from fuzzkit.loop.result import RunResult
from fuzzkit.studies.experiments import DEFAULT_GAINS, DEFAULT_LATENCY, experiment, press_experiment


@functools.cache
def _surface() -> Surface:
    return load_surface("macvicar_whelan")


@functools.cache
def _e1(latency: tuple[int, int]) -> RunResult:
    return run(experiment("E1"), "planar", "pi", seed=3, duration_s=2.5, latency=latency)


@pytest.mark.parametrize("d", [0, 1, 3])
def test_sensor_delay_shifts_the_controllers_input_by_exactly_d_samples(d: int) -> None:
    r = _e1((d, 0))
    assert r.latency_periods == (d, 0)
    n = len(r.t)
    # what the controller consumed in period k is what the sensor delivered in period k - d
    assert np.array_equal(r.force[d:], r.force_sensor[: n - d], equal_nan=True)
    # before that, the queue holds the reset sample (no sensor sample yet: NaN), d times
    assert np.all(np.isnan(r.force[:d]))
    # and the error the controller acted on is the set point minus that delayed sample
    active = ~np.isnan(r.force[:, 2]) & (r.t > (r.engaged_time_s or np.inf))
    assert active.sum() > 50
    assert np.allclose(r.e[active, 2], 10.0 - r.force[active, 2])


@pytest.mark.parametrize("c", [0, 2])
def test_command_delay_shifts_the_applied_correction_by_exactly_c_periods(c: int) -> None:
    r = _e1((0, c))
    rot = r.experiment.scenario.rotation
    applied = r.target_position - r.nominal_position  # base frame
    expected = (rot @ r.u.T).T  # the correction computed in each period, base frame
    # computed in period k, the plant moves with it in period k + 1 + c
    lag = 1 + c
    assert np.abs(r.u[:, 2]).max() > 1e-4  # the loop really corrects
    assert np.allclose(applied[lag:], expected[:-lag], atol=1e-12)
    assert np.allclose(applied[:lag], 0.0)


def test_default_latency_is_the_experiments_and_negative_latency_is_rejected() -> None:
    r = _e1(DEFAULT_LATENCY)
    assert run(experiment("E1"), "planar", "pi", seed=3, duration_s=0.1).latency_periods == (
        DEFAULT_LATENCY
    )
    assert r.latency_periods == DEFAULT_LATENCY == (1, 1)
    with pytest.raises(ConfigError, match="latency"):
        run(experiment("E1"), "planar", "pi", duration_s=0.1, latency=(-1, 0))


def _gains(controller: str, factor: float) -> dict[str, float]:
    g = dict(DEFAULT_GAINS[controller])
    for key in ("kp", "ki") if controller == "pi" else ("kx",):
        g[key] *= factor
    return g


@pytest.mark.slow
@pytest.mark.parametrize("controller", ["pi", "fuzzy-pi"])
def test_four_times_the_default_gains_are_stable_without_delay_and_unstable_at_5_periods(
    controller: str,
) -> None:
    """Pressing 10 N on the hammer (10 N/mm): the loop gain per period times the delay sets
    the stability (an integrator with gain g and d periods of delay is stable only for
    g < 2 sin(pi / (2 (2d + 1))))."""
    exp = press_experiment(1.0e4)
    surface = _surface() if controller == "fuzzy-pi" else None
    runs = {
        d: run(
            exp,
            "planar",
            controller,
            gains=_gains(controller, 4.0),
            surface=surface,
            seed=1,
            latency=(d, 0),
            duration_s=2.0,
        )
        for d in (0, 5)
    }
    steady = runs[0].force_true[-125:, 2]
    assert not runs[0].tripped
    assert abs(float(np.mean(steady)) - 10.0) < 0.3 and float(np.std(steady)) < 0.5
    # at 5 periods the force oscillates past the safety limit: the loop trips and backs off
    assert runs[5].tripped
    assert float(np.max(np.abs(runs[5].force_true[-50:]))) < 1.0
    # the same 5 periods with the default gains stay stable
    default = run(
        exp, "planar", controller, surface=surface, seed=1, latency=(5, 0), duration_s=2.0
    )
    assert not default.tripped and float(np.std(default.force_true[-125:, 2])) < 0.5


def test_stability_map_boundary_is_the_last_delay_of_the_first_stable_run() -> None:
    from fuzzkit.studies.latency_sweep import StabilityMap

    m = StabilityMap(
        "pi",
        (1.0, 2.0, 4.0),
        (0, 1, 2, 3),
        ((True, True, True, True), (True, True, False, True), (False, True, True, True)),
    )
    # a stable island past the first unstable delay does not count
    assert m.boundary() == {1.0: 3, 2.0: 1, 4.0: None}


@pytest.mark.slow
def test_the_stable_delay_shrinks_as_the_gain_grows_and_the_figure_is_written(
    tmp_path: Path,
) -> None:
    from fuzzkit.studies.latency_sweep import stability_map
    from fuzzkit.viz.latency import write_stability_png

    maps = [stability_map(c, (1.0, 3.0, 8.0), (0, 2, 4)) for c in ("pi", "fuzzy-pi")]
    for m in maps:
        bound = [-1 if b is None else b for b in m.boundary().values()]
        assert bound == sorted(bound, reverse=True), m
        assert bound[0] == 4 and bound[-1] == 0  # defaults survive 4 periods; 8x gains none
    png = write_stability_png(maps, tmp_path / "b.png")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
