"""The controller and axis names every layer spells, defined once.

A light module (no imports) so the command line can offer them as choices without loading
the controllers; :mod:`fuzzkit.control.spec`, the gains files, the studies, the analysis and
the CLI all take them from here. (``fuzzkit.codegen`` may not import :mod:`fuzzkit.control`:
its ``controller.KINDS`` / ``AXES`` are the plain-data mirror, held to these by
``tests/test_controller_codegen.py``.)
"""

from __future__ import annotations

#: Task axes in index order.
AXES = ("x", "y", "z")
#: Controller kinds: incremental PI (eq. 9) and fuzzy-PI (sec. 3.2.4); a gains file's
#: controllers, in file order.
KINDS = ("pi", "fuzzy-pi")
#: The scaling factors each kind takes (a spec's ``gains:`` per axis, the searched gains of a
#: tune): a PI's gains on the change of error and on the error (m/N), a fuzzy-PI's input scales
#: (1/N) and output scale (m per period).
GAIN_KEYS: dict[str, tuple[str, ...]] = {"pi": ("kp", "ki"), "fuzzy-pi": ("kp", "ki", "kx")}
#: What a gains file may add to them: the limits of the accumulated correction (m) and of its
#: step (m per period).
GAIN_LIMIT_KEYS = ("u_min", "u_max", "rate_limit")
#: Prefix of the adaptive controller names: ``adaptive-pi``, ``adaptive-fuzzy-pi``.
ADAPTIVE_PREFIX = "adaptive-"
#: The adaptive controllers ``--controller`` takes: the kit's stiffness schedule on a kind.
ADAPTIVE_CONTROLLERS = tuple(ADAPTIVE_PREFIX + kind for kind in KINDS)
#: Every controller ``simulate``, ``sweep`` and ``tune`` run: the two kinds, or either under
#: the kit's default stiffness schedule (docs/controller.md, "Adaptation").
RUN_CONTROLLERS = (*KINDS, *ADAPTIVE_CONTROLLERS)
