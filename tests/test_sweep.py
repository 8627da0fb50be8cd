"""Sweeps: the product expands as documented, every executor gives the same rows, the table and
figure are written; a real Dask cluster (scheduler + two worker processes) gives the same
results as the in-process run."""

from __future__ import annotations

import csv
import math
from pathlib import Path
from typing import Any

import pytest

from fuzzkit.cli import main
from fuzzkit.errors import ConfigError
from fuzzkit.loop.spec import RunSpec
from fuzzkit.studies.batch import execute, map_runs
from fuzzkit.studies.sweep import TIMING_COLUMNS, run_sweep, sweep_specs, write_table


def _strip(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    return [{k: v for k, v in r.items() if k not in TIMING_COLUMNS} for r in rows]


def _specs() -> list[RunSpec]:
    return sweep_specs(
        ["E1", "E2"],
        ["pi", "fuzzy-pi"],
        stiffnesses_n_per_mm=[10.0, 20.0],
        latencies=[(0, 0), (2, 1)],
        seeds=2,
        duration_s=2.0,
    )


def test_sweep_expands_the_cartesian_product_in_order() -> None:
    specs = _specs()
    assert len(specs) == 2 * 2 * 2 * 2 * 2
    assert len(set(specs)) == len(specs)
    assert specs[0] == RunSpec("E1", "pi", stiffness_n_per_mm=10.0, latency=(0, 0), duration_s=2.0)
    # without latencies, every run keeps its experiment's own (None)
    assert {s.latency for s in sweep_specs(["E1"], ["pi"])} == {None}
    assert [s.seed for s in specs[:4]] == [0, 1, 0, 1]
    assert specs[1].latency == (0, 0) and specs[2].latency == (2, 1)
    with pytest.raises(ConfigError, match="seeds"):
        sweep_specs(["E1"], ["pi"], seeds=0)


def _square(x: int) -> int:
    return x * x


def test_map_runs_keeps_order_with_a_process_pool() -> None:
    seen: list[int] = []
    assert map_runs(_square, list(range(7)), workers=2, progress=seen.append) == [
        x * x for x in range(7)
    ]
    assert seen[-1] == 7


def _slow_square(x: int) -> int:
    import time

    time.sleep(0.2)
    return x * x


def test_a_stopped_map_leaves_no_worker_process_behind() -> None:
    """Ctrl-C (here raised from the progress callback) drops the queued items, and the worker
    processes have ended when the executor closes: none outlives the command."""
    import multiprocessing

    from fuzzkit.studies.batch import BatchExecutor

    def stop(done: int) -> None:
        raise KeyboardInterrupt

    before = set(multiprocessing.active_children())
    with pytest.raises(KeyboardInterrupt), BatchExecutor(workers=2) as pool:
        pool.map(_slow_square, list(range(50)), progress=stop)
    assert set(multiprocessing.active_children()) <= before


@pytest.mark.slow
def test_process_pool_rows_equal_in_process_rows(tmp_path: Path) -> None:
    specs = _specs()[:8]
    local = run_sweep(specs, workers=1)
    pooled = run_sweep(specs, workers=2)
    assert _strip(pooled) == _strip(local)
    # the runs differ where the parameters say they should: the seed changes the noise
    assert local[0]["z_steady_state_error_mean"] != local[1]["z_steady_state_error_mean"]
    assert all(r["loop"] == "compiled" for r in local)


@pytest.mark.slow
@pytest.mark.xdist_group("dask")
def test_dask_local_cluster_gives_the_in_process_results(dask_scheduler: str) -> None:
    distributed = pytest.importorskip("distributed")
    specs = _specs()[:12]
    local = [execute(s) for s in specs]
    remote = map_runs(execute, specs, scheduler=dask_scheduler)
    with distributed.Client(dask_scheduler) as client:
        where = client.run(lambda: __import__("os").getpid())
    assert len(set(where.values())) == 2  # two worker processes really ran
    assert _strip(remote) == _strip(local)


def test_unreachable_scheduler_is_a_clear_error(monkeypatch: pytest.MonkeyPatch) -> None:
    from fuzzkit.studies import batch

    # the message does not depend on how long it waits: 1 s instead of the real 10 s
    monkeypatch.setattr(batch, "SCHEDULER_TIMEOUT", "1s")
    with pytest.raises(ConfigError, match="cannot reach the dask scheduler"):
        map_runs(execute, [RunSpec("E1", "pi", duration_s=0.1)], scheduler="tcp://127.0.0.1:9")


def test_table_is_written_as_csv_and_parquet(tmp_path: Path) -> None:
    rows = [
        {"experiment": "E1", "x_peak_force": 1.5, "z_overshoot_pct": None},
        {"experiment": "E2", "z_overshoot_pct": 3.0},
    ]
    write_table(rows, tmp_path / "t.csv")
    with open(tmp_path / "t.csv") as fh:
        got = list(csv.DictReader(fh))
    assert got == [
        {"experiment": "E1", "x_peak_force": "1.5", "z_overshoot_pct": ""},
        {"experiment": "E2", "x_peak_force": "", "z_overshoot_pct": "3.0"},
    ]
    pq = pytest.importorskip("pyarrow.parquet")
    write_table(rows, tmp_path / "t.parquet")
    table = pq.read_table(tmp_path / "t.parquet").to_pylist()
    assert table == [
        {"experiment": "E1", "x_peak_force": 1.5, "z_overshoot_pct": None},
        {"experiment": "E2", "x_peak_force": None, "z_overshoot_pct": 3.0},
    ]
    with pytest.raises(ConfigError, match=r"\.csv or \.parquet"):
        write_table(rows, tmp_path / "t.xlsx")


@pytest.mark.slow
def test_sweep_cli_writes_one_row_per_run_and_a_figure(tmp_path: Path) -> None:
    out = tmp_path / "runs.csv"
    code = main(
        [
            "sweep", "E1", "--controller", "pi,fuzzy-pi", "--stiffness", "10,20",
            "--latency", "0:0,1:1", "--seeds", "2", "--duration", "2.5", "--out", str(out),
            "--workers", "1", "--quiet",
        ]
    )  # fmt: skip
    assert code == 0
    with open(out) as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 2 * 2 * 2 * 2
    assert {(r["controller"], r["stiffness_n_per_mm"], r["sensor_delay"]) for r in rows} == {
        (c, k, s) for c in ("pi", "fuzzy-pi") for k in ("10.0", "20.0") for s in ("0", "1")
    }
    for r in rows:
        assert float(r["real_time_factor"]) > 0 and r["loop"] == "compiled"
        assert math.isfinite(float(r["z_peak_force"]))
    png = out.with_suffix(".png")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize(
    "args, match",
    [
        (["--latency", "1"], "SENSOR:COMMAND"),
        (["--controller", "pid"], "unknown 'pid'"),
        (["--stiffness", "ten"], "100, 100N/mm, 1e5N/m"),
        (["--seeds", "0"], "--seeds: expected an integer from 1"),
    ],
)
def test_sweep_cli_bad_arguments(
    args: list[str], match: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    try:
        code = main(["sweep", "E1", "--out", str(tmp_path / "r.csv"), "--quiet", *args])
    except SystemExit as exc:  # a value argparse refuses (--latency, --stiffness)
        code = exc.code
    assert code == 2
    assert match in capsys.readouterr().err
    assert not (tmp_path / "r.csv").exists()
