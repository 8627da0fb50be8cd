"""One set of floating-point kernels for the whole test run, whatever CPU it runs on.

numpy and OpenBLAS pick their kernels by the CPU at import time. On an AVX-512 machine numpy's
double ``sin``/``exp``/... (``X86_V4`` and up) and OpenBLAS's SkylakeX kernels round differently
in the last place from the AVX2 ones, and numpy's OpenBLAS and scipy's (which numba's
``np.linalg`` and matrix products call) are then different builds with different kernels. The
tests that compare trajectories bit for bit (tests/data/loop_digests.json,
tests/data/mujoco_digests.json, the compiled loop against the Python loop) were recorded with the
AVX2 kernels, so the suite pins them: OpenBLAS's Haswell kernels and numpy without its AVX-512
dispatch, where the CPU has what they need. A variable the user set is left as it is.

It must run before numpy is first imported (tests/conftest.py calls it first), and it sets the
environment, so the xdist workers and the ``fuzzkit`` subprocesses the tests start inherit it.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

#: numpy's dispatch targets above AVX2 (numpy 2.4's names; older names are not dispatched).
AVX512_TARGETS = ("X86_V4", "AVX512_ICL", "AVX512_SPR", "AVX512F", "AVX512_SKX", "AVX512_CLX",
                  "AVX512_CNL", "AVX512_KNL", "AVX512_KNM")  # fmt: skip


def _cpu_flags() -> set[str]:
    try:
        text = Path("/proc/cpuinfo").read_text(encoding="utf-8")
    except OSError:
        return set()
    for line in text.splitlines():
        if line.startswith("flags"):
            return set(line.split(":", 1)[1].split())
    return set()


def _numpy_avx512_targets() -> list[str]:
    """The AVX-512 targets this numpy dispatches to on this CPU (asked in a child process, so
    this one has not imported numpy when the variable is set)."""
    code = (
        "import numpy._core._multiarray_umath as m\n"
        "print(' '.join(t for t in m.__cpu_dispatch__ if m.__cpu_features__.get(t)))"
    )
    env = {k: v for k, v in os.environ.items() if k != "NPY_DISABLE_CPU_FEATURES"}
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True
    )
    return [t for t in out.stdout.split() if t in AVX512_TARGETS]


def pin_kernels() -> None:
    if "numpy" in sys.modules:
        raise RuntimeError(
            "tests/_dispatch.py: numpy was imported before the kernels were pinned; "
            "the bit-for-bit tests would run on this CPU's own kernels"
        )
    flags = _cpu_flags()
    if {"avx2", "fma"} <= flags:
        os.environ.setdefault("OPENBLAS_CORETYPE", "Haswell")
    if "avx512f" in flags and "NPY_DISABLE_CPU_FEATURES" not in os.environ:
        targets = _numpy_avx512_targets()
        if targets:
            os.environ["NPY_DISABLE_CPU_FEATURES"] = " ".join(targets)
