"""The rerun command-line tool, for tests that read back a recording (not a test module)."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest


def rerun_cli() -> str:
    """The ``rerun`` program beside this interpreter (rerun-sdk installs it), else on PATH;
    skips the calling test when there is none."""
    exe = Path(sys.executable).with_name("rerun")
    found = str(exe) if exe.exists() else shutil.which("rerun")
    if found is None:
        pytest.skip("the rerun CLI (rerun-sdk) is not on PATH")
    return found


def rrd_dump(path: Path, *flags: str) -> str:
    """``rerun rrd print FLAGS PATH``'s output (the file as the viewer reads it); fails the
    calling test when rerun cannot read the file."""
    res = subprocess.run(
        [rerun_cli(), "rrd", "print", *flags, str(path)], capture_output=True, text=True
    )
    assert res.returncode == 0, res.stderr
    return res.stdout


def entity_rows(path: Path, entity: str, component: str) -> tuple[list[int], list[object]]:
    """The temporal rows of ``entity`` in the recording at ``path``, in time order: their
    ``sim_time`` (ns) and the value of ``component`` (``"LineStrips3D:strips"`` ...) in each, read
    back with rerun's own reader."""
    import pyarrow as pa
    from rerun.chunk import RrdReader

    rows: list[tuple[int, object]] = []
    for chunk in RrdReader(path).stream():
        if chunk.entity_path != entity or chunk.is_static:
            continue
        batch = chunk.to_record_batch()
        times = batch.column("sim_time").cast(pa.int64()).to_pylist()
        rows.extend(zip(times, batch.column(component).to_pylist(), strict=True))
    rows.sort(key=lambda row: row[0])
    return [t for t, _ in rows], [v for _, v in rows]
