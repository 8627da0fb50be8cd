"""Python target: one standard-library module (``math`` only), computing in Python floats.

Every Python-specific choice of the generators is here; the templates beside this file lay the
spec objects out (``{name}`` in a file pattern is the rule base's or controller's name).
"""

from __future__ import annotations

import math
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from fuzzkit.codegen.backends.python.run import open_controller
from fuzzkit.codegen.lookup_table import LookupTable
from fuzzkit.codegen.target import Proof, Target
from fuzzkit.codegen.verify import verify_exact_python, verify_python
from fuzzkit.errors import CodegenError
from fuzzkit.fuzzy.model import RuleBase
from fuzzkit.fuzzy.validation import PYTHON_KEYWORDS


def literal(value: float, number_type: str) -> str:
    """A Python float constant: its ``repr`` (the shortest text that reads back exactly)."""
    if not math.isfinite(value):
        raise CodegenError(f"cannot emit the non-finite constant {value}")
    return repr(float(value))


def module_clash(name: str) -> str | None:
    """``NAME.py`` named like a standard module: its own ``import NAME`` would find it."""
    if name in sys.stdlib_module_names:
        return f"{name}.py would shadow the Python standard module {name!r}"
    return None


# Looked up at each call (not bound into TARGET) so that a test can give them fewer points.
def _verify_exact(rb: RuleBase, number_type: str, files: Mapping[str, str], **kw: Any) -> Proof:
    return verify_exact_python(rb, files, **kw)


def _verify_table(rb: RuleBase, table: LookupTable, files: Mapping[str, str], **kw: Any) -> Proof:
    return verify_python(rb, table, files, **kw)


TARGET = Target(
    name="python",
    folder=Path(__file__).parent,
    label="Python",
    number_types=("double",),
    default_number_type="double",
    type_names={"double": "float"},
    math_suffix={"double": ""},
    runtime={"double": "Python floats"},
    literal=literal,
    nan="_NAN",
    functions={"min": "min", "max": "max", "psum": "_psum"},
    reserved_words=PYTHON_KEYWORDS,
    module_clash=module_clash,
    # reprs are up to 23 characters: 4 a line keeps generated Python under 100 columns
    values_per_line={"table": 4, "exact": 4, "controller": 3},
    files={
        "table": {"{name}.py": "module.py.jinja"},
        "exact": {"{name}.py": "exact.py.jinja"},
        # interval type-2 exact inference (codegen.exact_type2): its own body
        "exact_type2": {"{name}.py": "exact.py.jinja"},
        # the fuzzy-PI surface is embedded (exact_body.py.jinja): one module, no import path
        "controller": {"{name}.py": "controller.py.jinja"},
    },
    visits_firing_cells=False,
    fast_centroid=True,
    verify_table=_verify_table,
    verify_exact=_verify_exact,
    open_controller=open_controller,
)
