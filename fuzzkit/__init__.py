"""fuzzkit: a fuzzy-logic controller design kit.

Author Mamdani rule bases in YAML, evaluate them exactly, compile them to lookup-table C and
pure-Python controllers, and verify the controllers in closed loop against simulated robots.

Quick start::

    import fuzzkit
    rb = fuzzkit.load("macvicar_whelan")              # a shipped name or a path
    fuzzkit.evaluate(rb, {"e": [0.3], "de": [-0.2]})  # {"du": array([...])}
    fuzzkit.evaluate_point(rb, e=0.3, de=-0.2)        # {"du": float}
    fuzzkit.explain(rb, {"e": 0.3, "de": -0.2})        # memberships, rules fired, output set
"""

from __future__ import annotations

import importlib
from typing import Any

__version__ = "0.1.0"

# Public names, resolved lazily so that importing a low module (fuzzkit.fuzzy.model) does not pull
# in numpy-heavy ones, and the CLI starts fast.
_EXPORTS = {
    "Engine": "fuzzkit.fuzzy.inference",
    "evaluate": "fuzzkit.fuzzy.inference",
    "evaluate_point": "fuzzkit.fuzzy.inference",
    "explain": "fuzzkit.fuzzy.explain",
    "load": "fuzzkit.formats.registry",
    "loads": "fuzzkit.formats.registry",
    "available": "fuzzkit.formats.registry",
    "dump": "fuzzkit.formats.yaml_writer",
}

__all__ = ["__version__", *sorted(_EXPORTS)]


def __dir__() -> list[str]:
    """The public names (resolved lazily) next to the module's own, for dir() and help()."""
    return sorted({*_EXPORTS, *(name for name in globals() if name.startswith("__"))})


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'fuzzkit' has no attribute {name!r}")
    return getattr(importlib.import_module(module), name)
