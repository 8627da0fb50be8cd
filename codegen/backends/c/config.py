"""C target: C99 for microcontrollers (no heap, ``static const`` data, every symbol prefixed).

Every C-specific choice of the generators is here; the templates beside this file lay the
spec objects out (``{name}`` in a file pattern is the rule base's or controller's name).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from fuzzkit.codegen.backends.c.run import open_controller
from fuzzkit.codegen.target import Target
from fuzzkit.codegen.verify import verify_c, verify_exact_c
from fuzzkit.errors import CodegenError
from fuzzkit.fuzzy.validation import C_KEYWORDS

#: Standard C headers (C99, C11): a rule base ``NAME`` generates ``NAME.h``, which an
#: ``#include <NAME.h>`` elsewhere in the firmware could pick up instead (with ``-I.``).
STANDARD_HEADERS = frozenset(
    """
    assert complex ctype errno fenv float inttypes iso646 limits locale math setjmp signal
    stdalign stdarg stdatomic stdbool stddef stdint stdio stdlib stdnoreturn string tgmath
    threads time uchar wchar wctype
    """.split()  # noqa: SIM905 (a word list reads better than 29 quoted strings)
)


def literal(value: float, number_type: str) -> str:
    """A C constant: 9 significant digits and ``f`` for float, 17 for double."""
    if not math.isfinite(value):
        raise CodegenError(f"cannot emit the non-finite constant {value}")
    if number_type == "float":
        text = format(float(np.float32(value)), ".9g")
        suffix = "f"
    else:
        text = format(float(value), ".17g")
        suffix = ""
    if not any(ch in text for ch in ".en"):
        text += ".0"
    return text + suffix


def module_clash(name: str) -> str | None:
    """``NAME.h`` named like a standard header (case-insensitive: macOS and Windows)."""
    if name.lower() in STANDARD_HEADERS:
        return f"{name}.h would shadow the C standard header <{name.lower()}.h>"
    return None


TARGET = Target(
    name="c",
    folder=Path(__file__).parent,
    label="C",
    number_types=("float", "double", "q15"),
    default_number_type="float",
    type_names={"float": "float", "double": "double", "q15": "int16_t"},
    math_suffix={"float": "f", "double": "", "q15": ""},
    runtime={
        "float": "float arithmetic",
        "double": "double arithmetic",
        "q15": "Q15 integer arithmetic",
    },
    literal=literal,
    nan="NAN",
    functions={"min": "{name}_min", "max": "{name}_max", "psum": "{name}_psum"},
    reserved_words=C_KEYWORDS,
    module_clash=module_clash,
    values_per_line={"table": 8, "exact": 6, "controller": 3},
    files={
        "table": {"{name}.h": "header.h.jinja", "{name}.c": "source.c.jinja"},
        "exact": {"{name}.h": "exact.h.jinja", "{name}.c": "exact.c.jinja"},
        # interval type-2 exact inference (codegen.exact_type2): the same header
        "exact_type2": {"{name}.h": "exact.h.jinja", "{name}.c": "exact_type2.c.jinja"},
        "controller": {"{name}.h": "controller.h.jinja", "{name}.c": "controller.c.jinja"},
        # a fuzzy-PI controller's surface: the exact method as a sibling unit NAME_surface
        "surface": {"{name}.h": "exact.h.jinja", "{name}.c": "exact.c.jinja"},
        # ... an interval type-2 rule base's (codegen.exact_type2)
        "surface_type2": {"{name}.h": "exact.h.jinja", "{name}.c": "exact_type2.c.jinja"},
        # ... or, for a spec's surface: {method: table}, its lookup table
        "surface_table": {"{name}.h": "header.h.jinja", "{name}.c": "source.c.jinja"},
    },
    visits_firing_cells=True,
    fast_centroid=True,
    # the same bits on a microcontroller's C library (newlib) as on the host's (glibc)
    portable_math={"float": ("erfc", "exp", "log", "pow")},
    verify_table=verify_c,
    verify_exact=verify_exact_c,
    open_controller=open_controller,
)
