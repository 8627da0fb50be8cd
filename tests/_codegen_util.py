"""Shared helpers of the codegen tests (not a test module)."""

from __future__ import annotations

import functools
import shutil

import pytest

import fuzzkit
from codegen.emit import emit
from codegen.lut import LookupTable, NumberType, make_table
from codegen.toolchain import find_compiler
from fuzzkit.model import RuleBase

#: Small resolutions keep the tests fast; the bound is what is checked, whatever it is.
RESOLUTION = {"macvicar_whelan": 25, "paper_table1": 25, "gaussian5": 17, "three_input": 9}

CC = find_compiler()
needs_cc = pytest.mark.needs_cc
skip_no_cc = pytest.mark.skipif(CC is None, reason="no C compiler found (cc, gcc, clang or $CC)")
CLANG = shutil.which("clang")


@functools.cache
def rulebase(name: str) -> RuleBase:
    return fuzzkit.load(name)


@functools.cache
def table(name: str, number_type: NumberType) -> LookupTable:
    """A table of a shipped rule base at the test resolution (no tolerance: bound reported)."""
    return make_table(rulebase(name), number_type=number_type, resolution=RESOLUTION[name])


def sources(name: str, target: str, number_type: NumberType) -> dict[str, str]:
    return emit(rulebase(name), table(name, number_type), target)
