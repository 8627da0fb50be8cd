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
