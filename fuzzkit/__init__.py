"""fuzzkit: a fuzzy-logic controller design kit.

Author Mamdani rule bases in YAML, evaluate them exactly, compile them to lookup-table C and
pure-Python controllers, and verify the controllers in closed loop against simulated robots.

Quick start::

    import fuzzkit
    rb = fuzzkit.load("macvicar_whelan")          # a shipped name or a path
    fuzzkit.evaluate(rb, {"e": [0.3], "de": [-0.2]})  # {"du": array([...])}
    fuzzkit.evaluate_point(rb, e=0.3, de=-0.2)      # {"du": float}
"""

from __future__ import annotations

__version__ = "0.1.0"

from fuzzkit.inference import Engine, evaluate, evaluate_point
from fuzzkit.registry import available, load, loads

__all__ = [
    "Engine",
    "__version__",
    "available",
    "evaluate",
    "evaluate_point",
    "load",
    "loads",
]
