"""No silent fallback to the reference (issue 37 item 2): a run the compiled loop does not take
(the tilt scenario's tool weight, drifting bias and tilt on arm6) runs the spec's generated C
controller in the Python loop, says so in ``loop`` and ``controller_impl``; the MuJoCo plants,
which the compiled loop runs now, run it there; and ``fuzzkit replay SPEC --forces run.csv
--impl c`` reproduces its corrections to 0 m with the same status bits in every period. The
reference stays the independent check: on the same plant, the reference run's forces follow
the generated run's to within the rounding of two implementations of one arithmetic.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from _codegen_util import needs_cc
from _pairwise import verify
from _replay_logs import read_out

from fuzzkit.cli import main
from fuzzkit.loop.spec import RunSpec
from fuzzkit.studies.batch import run_spec
from fuzzkit.studies.run_table import run_csv

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "docs" / "examples"
SPEC = ROOT / "tests" / "data" / "user" / "spec_swapped.yaml"

pytestmark = needs_cc

#: (scenario, plant, spec, fault, duration): what each run is (E1's first contact: 1.85 s)
RUNS = {
    "mujoco": ("E1", "mujoco", SPEC, "spike", 2.4),
    "mujoco-elastic": ("E1", "mujoco-elastic", SPEC, "nan", 2.4),
    "tilt-arm6": (
        str(EXAMPLES / "tilt.yaml"),
        "arm6",
        EXAMPLES / "controller_tilt.yaml",
        None,
        3.0,
    ),
}


def _run(name: str, impl: str = "auto") -> object:
    scenario, plant, spec, fault, duration = RUNS[name]
    return run_spec(
        RunSpec(
            scenario,
            plant=plant,
            controller_spec=str(spec),
            fault=fault,
            duration_s=duration,
            controller_impl=impl,
        )
    )


@pytest.mark.parametrize(
    "name", [pytest.param(n, marks=[verify] if n == "mujoco-elastic" else []) for n in sorted(RUNS)]
)
def test_the_generated_controller_runs_and_replays_to_0_m_with_the_same_status(
    name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    result: object = _run(name)
    loop, impl = result.loop, result.controller_impl  # type: ignore[attr-defined]
    ran = "compiled" if name.startswith("mujoco") else "python"
    assert loop.startswith(ran), loop
    assert impl.startswith("generated C controller (double)") and impl.endswith(f"({ran} loop)")
    assert ("fallback" in loop) == (name == "tilt-arm6")  # the compiled loop lacks the tilt
    assert not result.tripped and result.engaged_time_s is not None  # type: ignore[attr-defined]
    csv = tmp_path / "run.csv"
    csv.write_text(run_csv(result), encoding="utf-8")  # type: ignore[arg-type]
    out = tmp_path / "u.csv"
    spec = RUNS[name][2]
    assert main(["replay", str(spec), "--forces", str(csv), "--out", str(out), "--impl", "c"]) == 0
    assert "largest difference from the run's corrections (u<a>_m): 0 m" in capsys.readouterr().out
    header, rows = read_out(out)
    replayed_status = rows[:, header.index("status")].astype(np.int64)
    assert np.array_equal(replayed_status, result.status)  # type: ignore[attr-defined]
    u = rows[:, [header.index(c) for c in ("ux", "uy", "uz")]]
    assert np.array_equal(u, result.u)  # type: ignore[attr-defined]
    assert float(np.max(np.abs(u))) > 1e-4  # the controller corrected


@pytest.mark.parametrize("name", ["mujoco", pytest.param("tilt-arm6", marks=verify)])
def test_the_reference_on_request_follows_the_generated_run(name: str) -> None:
    generated, reference = _run(name), _run(name, impl="reference")
    assert "generated" not in reference.controller_impl  # type: ignore[attr-defined]
    assert reference.loop == "python"  # type: ignore[attr-defined]
    # one arithmetic in two implementations: the exact engine against the generated exact C
    diff = np.nanmax(np.abs(generated.force_true - reference.force_true))  # type: ignore[attr-defined]
    assert diff < 1e-6  # N


def test_without_a_compiler_the_mujoco_run_executes_the_generated_python(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from fuzzkit.loop.compiled import generated_controller

    monkeypatch.setenv("CC", "/nonexistent/cc")
    monkeypatch.setattr(generated_controller, "_LOADED", {})
    monkeypatch.setenv("FUZZKIT_CACHE_DIR", "/nonexistent/cache")
    result = _run("mujoco")
    impl = result.controller_impl  # type: ignore[attr-defined]
    assert impl.startswith("generated Python controller user_swapped_controller"), impl
    assert "no C compiler found" in impl


def test_tuning_on_mujoco_prices_the_generated_controller() -> None:
    """No stand-in surface: a tune on a plant without a compiled loop runs each candidate's
    generated controller, which the spec's reference follows."""
    from fuzzkit.control.spec_reader import load_spec
    from fuzzkit.studies.experiments import experiment, with_spec
    from fuzzkit.studies.tuning import CaseRunner, TuningProblem

    exp = with_spec(experiment("E1"), load_spec(SPEC))
    problem = TuningProblem.build([exp], "fuzzy-pi", str(SPEC.parent / "force_names_swapped.yaml"),
                                  "mujoco", (10.0,), horizon_s=2.5)  # fmt: skip
    gains = {"kp": 0.25, "ki": 0.06, "kx": 2.5e-4}
    run = CaseRunner(problem).run_case(0, gains, 2.5)
    assert run.controller_impl.startswith("generated C controller (double) user_swapped")
    reference = CaseRunner(replace_impl(problem, "reference")).run_case(0, gains, 2.5)
    assert "generated" not in reference.controller_impl
    assert float(np.nanmax(np.abs(run.force_true - reference.force_true))) < 1e-6  # N


def replace_impl(problem: object, impl: str) -> object:
    import dataclasses

    return dataclasses.replace(problem, controller_impl=impl)  # type: ignore[type-var]
