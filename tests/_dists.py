"""The package built as a user or a release job builds it (not a test module)."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def build_dists(release: bool, base: Path) -> tuple[Path, Path]:
    """(wheel, sdist) built from a clean copy of the repository under ``base``: the release
    build (isolated, the wheel from the sdist) or the quick one (this environment's
    setuptools, both from the copy). ``tests/conftest.py``'s ``built_dists`` builds each
    kind once per run."""
    tmp = base / ("release" if release else "quick")
    src = tmp / "src"
    shutil.copytree(
        ROOT,
        src,
        ignore=shutil.ignore_patterns(
            ".git", ".venv*", "build", "dist", "*.egg-info", "__pycache__", ".*cache", "*-out"
        ),
    )
    out = tmp / "dist"
    # the quick build skips the dependency check: build-system.requires names `wheel`, which
    # setuptools (>= 70.1) no longer needs to build one, and which the lock does not install
    how = [] if release else ["--sdist", "--wheel", "--no-isolation", "--skip-dependency-check"]
    built = subprocess.run(
        [sys.executable, "-m", "build", *how, "--outdir", str(out), str(src)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert built.returncode == 0, built.stdout[-3000:] + built.stderr[-3000:]
    (wheel,) = out.glob("*.whl")
    (sdist,) = out.glob("*.tar.gz")
    return wheel, sdist
