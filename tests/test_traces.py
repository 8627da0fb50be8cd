"""Tests of the Rerun recordings: written atomically and readable back by rerun itself."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import numpy as np
import pytest
from _rerun import entity_rows, rerun_cli

from fuzzkit.errors import ConfigError
from fuzzkit.loop.python_loop import run
from fuzzkit.loop.result import RunResult
from fuzzkit.studies.experiments import experiment
from fuzzkit.viz.traces_planar import write_rrd


@pytest.fixture(scope="module")
def result() -> RunResult:
    return run(experiment("E1"), "planar", "pi", seed=1, duration_s=2.5)


def test_rrd_is_valid_and_has_every_entity(result: RunResult, tmp_path: Path) -> None:
    out = write_rrd(result, tmp_path / "e1.rrd")
    assert out.stat().st_size > 0
    assert list(tmp_path.iterdir()) == [out]  # no temporary file left behind
    cli = rerun_cli()
    verify = subprocess.run([cli, "rrd", "verify", str(out)], capture_output=True, text=True)
    assert verify.returncode == 0, verify.stderr
    listing = subprocess.run([cli, "rrd", "print", str(out)], capture_output=True, text=True)
    assert listing.returncode == 0, listing.stderr
    rows: dict[str, int] = {}
    for m in re.finditer(r"with (\d+) rows .*? - (/\S+) - ", listing.stdout):
        rows[m.group(2)] = rows.get(m.group(2), 0) + int(m.group(1))
    expected = [
        "/forces/z/measured",
        "/forces/z/setpoint",
        "/forces/x/measured",
        "/forces/x/setpoint",
        "/control/error/z/e",
        "/control/error/z/de",
        "/control/correction/z/du",
        "/control/correction/z/u",
        "/control/correction/x/u",
        "/joints/q1",
        "/joints/q2",
        "/world/arm",
        "/world/tool",
        "/world/contacts",
        "/world/nominal_path",
        "/world/environment/table",
        "/world/environment/hammer",
    ]
    missing = [e for e in expected if e not in rows]
    assert not missing, f"missing entities {missing}; found {sorted(rows)}"
    # Every controller period of the force series is there (plus the static style row).
    assert rows["/forces/z/measured"] >= len(result.t)
    assert "/control/correction/y/u" not in rows  # y is not force-controlled in E1


def test_the_scene_holds_the_arm_and_contacts_of_every_drawn_period(
    result: RunResult, tmp_path: Path
) -> None:
    """Read back: every 5th period's arm (base -> joints -> tool tip) and contact points, at
    the same instants as that period's force sample."""
    out = write_rrd(result, tmp_path / "e1.rrd", geometry_every=5)
    force_times, _ = entity_rows(out, "/forces/z/measured", "Scalars:scalars")
    times, strips = entity_rows(out, "/world/arm", "LineStrips3D:strips")
    frames = range(0, len(result.t), 5)
    assert times == [force_times[k] for k in frames]
    for k, strip in zip(frames, strips, strict=True):
        np.testing.assert_array_equal(np.asarray(strip[0]), result.arm_points[k].astype(np.float32))
    times, contacts = entity_rows(out, "/world/contacts", "Points3D:positions")
    assert times == [force_times[k] for k in frames]
    counts = [len(result.contact_points[k].reshape(-1, 3)) for k in frames]
    assert [len(c) for c in contacts] == counts and 0 < sum(counts) < len(counts) * 10
    touching = next(i for i, n in enumerate(counts) if n)
    np.testing.assert_array_equal(
        np.asarray(contacts[touching]),
        result.contact_points[frames[touching]].reshape(-1, 3).astype(np.float32),
    )


def test_bad_output_path_writes_nothing(result: RunResult, tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="does not exist"):
        write_rrd(result, tmp_path / "missing" / "x.rrd")
    with pytest.raises(ConfigError, match="is a directory"):
        write_rrd(result, tmp_path)
    assert list(tmp_path.iterdir()) == []


def test_cli_simulate_writes_rrd(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from fuzzkit.cli import main

    out = tmp_path / "run.rrd"
    assert main(["simulate", "E1", "--controller", "pi", "--rrd", str(out)]) == 0
    assert out.stat().st_size > 0
    assert f"wrote {out}" in capsys.readouterr().out
