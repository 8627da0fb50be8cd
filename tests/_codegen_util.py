"""Shared helpers of the fuzzkit.codegen tests (not a test module)."""

from __future__ import annotations

import functools
import shutil
import subprocess
import tempfile
from pathlib import Path

import pytest
from _artefacts import shared

import fuzzkit
from fuzzkit.codegen.emit import emit
from fuzzkit.codegen.lookup_table import LookupTable, NumberType
from fuzzkit.codegen.table_search import make_table
from fuzzkit.codegen.toolchain import SANITIZE_FLAGS, find_compiler
from fuzzkit.fuzzy.model import RuleBase

#: Small resolutions keep the tests fast; the bound is what is checked, whatever it is.
RESOLUTION = {
    "macvicar_whelan": 25,
    "macvicar_whelan_it2": 25,
    "paper_table1": 25,
    "gaussian5": 17,
    "three_input": 9,
}

#: One input far from 0 with a knot float32 cannot hold (float C) and few Q15 codes.
OFFSET_YAML = """
name: offset_1d
description: One input far from 0 with a knot float32 cannot hold (1000.3).
inputs:
  a:
    range: [1000, 1002]
    terms:
      lo: {shape: triangle, points: [999, 1000, 1000.3]}
      mid: {shape: triangle, points: [1000, 1000.3, 1002]}
      hi: {shape: triangle, points: [1000.3, 1002, 1003]}
outputs:
  y:
    range: [-500, 500]
    terms:
      neg: {shape: triangle, points: [-700, -500, -300]}
      zer: {shape: triangle, points: [-200, 0, 200]}
      pos: {shape: triangle, points: [300, 500, 700]}
operators: {and: min, or: max, implication: min, aggregation: max}
defuzzifier: weighted_average
rules:
  - {if: {a: lo}, then: {y: neg}}
  - {if: {a: mid}, then: {y: zer}}
  - {if: {a: hi}, then: {y: pos}}
"""

CC = find_compiler()
needs_cc = pytest.mark.needs_cc
skip_no_cc = pytest.mark.skipif(CC is None, reason="no C compiler found (cc, gcc, clang or $CC)")
CLANG = shutil.which("clang")


@functools.cache
def _sanitizer_probe(cc: tuple[str, ...]) -> str | None:
    """Why ``cc`` cannot build and run a trivial program with :data:`SANITIZE_FLAGS`, or
    None when it can. Probed once per compiler and test process."""
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        (folder / "probe.c").write_text("int main(void) { return 0; }\n")
        for argv in ([*cc, *SANITIZE_FLAGS, "-o", "probe", "probe.c"], [str(folder / "probe")]):
            try:
                done = subprocess.run(
                    argv, cwd=folder, capture_output=True, text=True, timeout=120, check=False
                )
            except OSError as exc:
                return f"{argv[0]}: {exc}"
            if done.returncode != 0:
                return f"{' '.join(argv)}: exit {done.returncode}: {done.stderr.strip()}"
    return None


def require_sanitizers(cc: list[str]) -> None:
    """Skip the calling test when ``cc`` cannot link (or run) an address- and
    undefined-sanitized trivial program; any later failure of the real build is a failure."""
    reason = _sanitizer_probe(tuple(cc))
    if reason is not None:
        pytest.skip(f"this compiler cannot build sanitized programs: {reason}")


@functools.cache
def rulebase(name: str) -> RuleBase:
    return fuzzkit.load(name)


@functools.cache
def table(name: str, number_type: NumberType) -> LookupTable:
    """A table of a shipped rule base at the test resolution (no tolerance: bound reported),
    built once per test run (a table's search and certification take seconds)."""
    rb, resolution = rulebase(name), RESOLUTION[name]
    key = f"lookup table|{rb!r}|{number_type}|{resolution}"
    return shared(key, lambda: make_table(rb, number_type=number_type, resolution=resolution))


def sources(name: str, target: str, number_type: NumberType) -> dict[str, str]:
    return emit(rulebase(name), table(name, number_type), target)
