"""An interval type-2 rule base in the closed loop (issue 43 item 1), through the command line.

A controller spec naming ``macvicar_whelan_it2`` (``docs/examples/controller_it2.yaml``, its
surface exact IT2 inference, ``codegen/exact_type2.py``; or a table of it) simulates on every
plant through its generated controller, replays through the generated C to 0 m with identical
status bits, sweeps, tunes and exports as an FMU (``tests/test_fmu.py``). The loop's
corrections follow the brute-force IT2 reference (``tests/_type2_reference.py``, an
independent computation), and not the type-1 surface. ``make test`` runs a covering set of
plant x implementation x fault x latency; ``make verify`` the whole product.
"""

from __future__ import annotations

import csv
import itertools
import json
import re
from pathlib import Path

import numpy as np
import pytest
from _codegen_util import needs_cc
from _pairwise import pairwise
from _replay_logs import replayed_difference, reproduces, run_cli
from _type2_reference import centroid_interval

from fuzzkit.formats.registry import load
from fuzzkit.fuzzy.inference import Engine
from fuzzkit.fuzzy.type2_model import Type2RuleBase

REPO = Path(__file__).resolve().parent.parent
SPEC = REPO / "docs" / "examples" / "controller_it2.yaml"
TYPE1_SPEC = REPO / "docs" / "examples" / "controller.yaml"

pytestmark = needs_cc

AXES = (
    ("planar", "arm6", "mujoco", "mujoco-elastic"),
    ("c", "python"),
    ("none", "spike"),
    ("1:1", "2:3"),
)
COVERING = pairwise(AXES)
FULL = [r for r in itertools.product(*AXES) if r not in COVERING]


def _ok(capsys: pytest.CaptureFixture[str], *argv: str) -> str:
    code, out, err = run_cli(capsys, *argv)
    assert code == 0, f"fuzzkit {' '.join(argv)}: exit {code}\n{out}\n{err}"
    return out


def _columns(path: Path, *names: str) -> list[np.ndarray]:
    with path.open(encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    return [np.array([float(r[n]) for r in rows]) for n in names]


def _run_and_replay(
    plant: str,
    impl: str,
    fault: str,
    latency: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    run_csv = tmp_path / "run.csv"
    out = _ok(
        capsys, "simulate", "E1", "--spec", str(SPEC), "--plant", plant, "--controller-impl",
        impl, "--fault", fault, "--latency", latency, "--csv", str(run_csv), "--json",
    )  # fmt: skip
    run = json.loads(out[out.index("{") :])
    assert run["plant"] == plant and not run["tripped"]
    want = "generated C controller" if impl == "c" else "generated Python controller"
    assert want in run["controller_impl"]
    assert run["axes"]["z"]["peak_force_true"] > 5.0  # it pressed
    (uz,) = _columns(run_csv, "uz_m")
    assert np.abs(uz).max() > 1e-4
    if impl == "c":  # the same code on the same samples: bit for bit
        assert replayed_difference(capsys, SPEC, run_csv, "c") == 0.0
    assert reproduces(capsys, SPEC, run_csv, "c")  # status bits equal in every row


@pytest.mark.parametrize(("plant", "impl", "fault", "latency"), COVERING)
def test_an_it2_spec_runs_on_every_plant_and_replays(
    plant: str, impl: str, fault: str, latency: str, tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:  # fmt: skip
    _run_and_replay(plant, impl, fault, latency, tmp_path, capsys)


@pytest.mark.verify
@pytest.mark.parametrize(("plant", "impl", "fault", "latency"), FULL)
def test_an_it2_spec_runs_on_every_plant_and_replays_full(
    plant: str, impl: str, fault: str, latency: str, tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:  # fmt: skip
    _run_and_replay(plant, impl, fault, latency, tmp_path, capsys)


def test_the_loop_evaluates_the_it2_surface(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # the reference controller (Python loop) records the e, de its surface read: its
    # corrections are the brute force's IT2 output (20001 samples: quadrature error below
    # 1e-7), and visibly not the type-1 surface's; the same run replays through the C
    run_csv = tmp_path / "ref.csv"
    _ok(capsys, "simulate", "E1", "--spec", str(SPEC), "--controller-impl", "reference",
        "--csv", str(run_csv))  # fmt: skip
    e, de, du, bits = _columns(run_csv, "ez_n", "dez_n", "duz_m", "status_bits")
    status = bits.astype(np.int64)
    stepped = (status & 1 > 0) & (status & (2 | 4 | 16) == 0)  # engaged, not held/tripped/clamped
    assert stepped.sum() > 500
    x, y = np.clip(0.05 * e[stepped], -1, 1), np.clip(0.2 * de[stepped], -1, 1)
    it2 = load("macvicar_whelan_it2")
    assert isinstance(it2, Type2RuleBase)
    rows = np.linspace(0, x.size - 1, 12).astype(int)
    for k in rows:
        y_l, y_r = centroid_interval(it2, {"e": x[k], "de": y[k]}, 20001)
        assert abs(du[stepped][k] / 2e-4 - 0.5 * (y_l + y_r)) < 1e-7
    type1 = Engine(load("macvicar_whelan")).evaluate({"e": x, "de": y})["du"]
    assert np.abs(du[stepped] / 2e-4 - type1).max() > 1e-2
    assert reproduces(capsys, SPEC, run_csv, "c")


def test_simulate_with_an_it2_rule_base_runs_its_exact_code(
    capsys: pytest.CaptureFixture[str],
) -> None:
    runs = {}
    for rb in ("macvicar_whelan_it2", "macvicar_whelan"):
        out = _ok(capsys, "simulate", "E1", "--rulebase", rb, "--plant", "arm6", "--json")
        runs[rb] = json.loads(out[out.index("{") :])
    it2 = runs["macvicar_whelan_it2"]
    assert "generated C controller" in it2["controller_impl"] and not it2["tripped"]
    # another controller than the type-1 one on the same task
    assert (
        it2["axes"]["z"]["overshoot_pct"] != runs["macvicar_whelan"]["axes"]["z"]["overshoot_pct"]
    )


def test_an_it2_spec_sweeps_and_tunes(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    runs = tmp_path / "runs.csv"
    _ok(capsys, "sweep", "E1", "--spec", str(SPEC), "--stiffness", "5,50", "--plant", "arm6",
        "--workers", "1", "--quiet", "--out", str(runs))  # fmt: skip
    with runs.open(encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["stiffness_n_per_mm"] for r in rows] == ["5.0", "50.0"]
    assert {r["rulebase"] for r in rows} == {"macvicar_whelan_it2"}
    assert all("generated C controller" in r["controller_impl"] for r in rows)
    tuned = tmp_path / "tuned.yaml"
    _ok(capsys, "tune", "E1", "--spec", str(SPEC), "--plant", "planar", "--budget", "10",
        "--workers", "1", "--quiet", "--out", str(tmp_path / "g.yaml"), "--spec-out",
        str(tuned))  # fmt: skip
    text = tuned.read_text(encoding="utf-8")
    assert "rulebase: macvicar_whelan_it2" in text and "method: table" not in text
    out = _ok(capsys, "simulate", "E1", "--spec", str(tuned), "--json")
    assert not json.loads(out[out.index("{") :])["tripped"]


def test_an_it2_spec_on_a_table_surface_runs_and_replays(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # the table of the exact IT2 engine, for targets that want one: the same loop, replayed
    table = _table_spec(tmp_path, 33)
    run_csv = tmp_path / "run.csv"
    out = _ok(capsys, "simulate", "E1", "--spec", str(table), "--plant", "arm6", "--csv",
              str(run_csv), "--json")  # fmt: skip
    assert not json.loads(out[out.index("{") :])["tripped"]
    assert replayed_difference(capsys, table, run_csv, "c") == 0.0
    # another controller than the exact spec's on the same samples
    assert replayed_difference(capsys, SPEC, run_csv, "c") > 1e-7


@pytest.mark.verify  # about 19 s (a 65 x 65 table of the exact IT2 engine, twice)
def test_stability_certifies_the_it2_table_that_ships_against_a_dense_grid(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # on a table surface the certificate's phi = F(x, y) / (x + y) comes from the deployed
    # table's triangles; the table's own interpolation on a 257 x 257 grid (which holds its
    # 65 x 65 nodes) stays inside it and reaches both ends. The exact surface's bounds come
    # from a denser table, and the certificate says they do not cover it.
    from fuzzkit.codegen.controller import surface_table
    from fuzzkit.control.controllers import lookup_table_surface

    table_spec = _table_spec(tmp_path, 65)
    report = _stability(capsys, table_spec)
    fuzzy = report["model"]["fuzzy"]
    assert fuzzy["bounds_cover_deployed_surface"] is True and fuzzy["bounds"] == "phi"
    lo, hi = fuzzy["phi"]
    f = lookup_table_surface(surface_table(load("macvicar_whelan_it2"), None, 65))
    g = np.linspace(-1.0, 1.0, 257)
    phi = np.array([f(x, y) / (x + y) for x in g for y in g if abs(x + y) > 1e-6])
    assert lo - 1e-12 <= phi.min() and phi.max() <= hi + 1e-12
    assert phi.min() - lo < 1e-9 and hi - phi.max() < 1e-9
    assert all(c["certified"] for c in report["cells"])


@pytest.mark.verify
def test_stability_of_the_exact_it2_surface_says_its_bounds_do_not_cover_it(
    capsys: pytest.CaptureFixture[str],
) -> None:
    # the exact surface's phi comes from a 129-point table of it (issue 40's sound bounds
    # are not used yet): the certificate must say that they do not cover the deployed surface
    fuzzy = _stability(capsys, SPEC)["model"]["fuzzy"]
    assert fuzzy["bounds_cover_deployed_surface"] is False and fuzzy["surface_error_bound"] > 0


def _table_spec(tmp_path: Path, resolution: int) -> Path:
    """The IT2 spec on a ``resolution`` x ``resolution`` table of its exact surface."""
    text = SPEC.read_text(encoding="utf-8")
    path = tmp_path / "table_it2.yaml"
    surface = f"surface: {{method: table, resolution: {resolution}}}"
    path.write_text(re.sub(r"(?m)^surface: .*$", surface, text), encoding="utf-8")
    return path


def _stability(capsys: pytest.CaptureFixture[str], spec: Path) -> dict:  # type: ignore[type-arg]
    out = _ok(capsys, "stability", "regulate", "--spec", str(spec), "--plant", "planar",
              "--stiffness", "5", "--latency", "1:1", "--json")  # fmt: skip
    return dict(json.loads(out[out.index("{") :]))
