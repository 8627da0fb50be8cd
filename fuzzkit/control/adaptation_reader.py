"""The ``adaptation:`` section of a controller-spec YAML -> :class:`Adaptation`, located.

Called by :mod:`fuzzkit.control.spec_reader` with its reader, so problems are reported as
``file:line:col`` like the rest of the spec. ``adaptation: none`` (or a bare mode name) is the
short form of ``{mode: none}``; the keys a mode takes are listed in ``docs/controller.md``.
"""

from __future__ import annotations

import math
from typing import Protocol

from yaml.nodes import Node, ScalarNode

from fuzzkit.control.adaptation_spec import MODES, Adaptation, Band, Estimator, SpecPath


class _SpecReader(Protocol):
    """What this module uses of ``fuzzkit.control.spec_reader``'s reader (which calls it)."""

    where: dict[SpecPath, Node]
    quiet: set[SpecPath]

    def name(self, node: Node, what: str) -> str | None: ...
    def error(self, node: Node, message: str) -> None: ...
    def number(self, node: Node, what: str) -> float | None: ...
    def sequence(self, node: Node, what: str) -> list[Node] | None: ...
    def section(
        self,
        node: Node,
        path: SpecPath,
        allowed: tuple[str, ...],
        required: tuple[str, ...] = (),
    ) -> dict[str, Node]: ...
    def word(self, entries: dict[str, Node], key: str, what: str, default: str) -> str: ...
    def real(
        self, entries: dict[str, Node], path: SpecPath, default: float = math.nan
    ) -> float: ...
    def optional_real(
        self, entries: dict[str, Node], path: SpecPath, default: float | None
    ) -> float | None: ...
    def count(self, entries: dict[str, Node], path: SpecPath, default: int) -> int: ...


#: The keys each mode takes (``mode`` always).
MODE_KEYS = {
    "none": ("mode",),
    "stiffness-scheduled": ("mode", "estimator", "bands", "inverse_n_mm", "dwell_s"),
    "self-tuning": ("mode", "alpha", "error_n", "change_n"),
}
ESTIMATOR_KEYS = (
    "window_periods",
    "delay_periods",
    "forgetting",
    "min_step_m",
    "min_force_n",
    "initial_n_mm",
    "range_n_mm",
    "inner_loop",
)
INNER_KEYS = ("q", "a", "g")
BAND_KEYS = ("up_to_n_mm", "scale")
ALPHA_KEYS = ("min", "max")
BASE = ("adaptation",)


def read_adaptation(r: _SpecReader, node: Node) -> Adaptation:
    """The adaptation section at ``node`` (a mode name or a mapping); problems go to ``r``."""
    what = f"an adaptation mode ({', '.join(MODES)})"
    if isinstance(node, ScalarNode):
        mode = r.name(node, what)
        r.where[BASE] = node
        if mode is None:
            r.quiet.add(BASE)
            return Adaptation()
        return Adaptation(mode=mode)
    every = tuple(dict.fromkeys(k for keys in MODE_KEYS.values() for k in keys))
    top = r.section(node, BASE, every, ("mode",))
    mode = r.word(top, "mode", what, "none") if "mode" in top else "none"
    if "mode" in top and mode not in MODES:
        return Adaptation(mode=mode)
    for key, value in top.items():
        if key not in MODE_KEYS[mode]:
            r.error(value, f"adaptation.{key} does not apply to mode {mode}")
    d = Adaptation()
    if mode == "stiffness-scheduled":
        return Adaptation(
            mode=mode,
            estimator=_estimator(r, top.get("estimator")),
            bands=_bands(r, top.get("bands")),
            dwell_s=r.real(top, (*BASE, "dwell_s"), d.dwell_s),
            inverse_n_mm=r.optional_real(top, (*BASE, "inverse_n_mm"), None),
        )
    if mode == "self-tuning":
        alpha = r.section(top["alpha"], (*BASE, "alpha"), ALPHA_KEYS) if "alpha" in top else {}
        return Adaptation(
            mode=mode,
            alpha_min=r.real(alpha, (*BASE, "alpha", "min"), d.alpha_min),
            alpha_max=r.real(alpha, (*BASE, "alpha", "max"), d.alpha_max),
            error_n=r.optional_real(top, (*BASE, "error_n"), None),
            change_n=r.optional_real(top, (*BASE, "change_n"), None),
        )
    return Adaptation(mode=mode)


def _estimator(r: _SpecReader, node: Node | None) -> Estimator:
    d = Estimator()
    if node is None:
        return d
    path = (*BASE, "estimator")
    e = r.section(node, path, ESTIMATOR_KEYS)
    low, high = d.k_min_n_mm, d.k_max_n_mm
    if "range_n_mm" in e:
        items = r.sequence(e["range_n_mm"], "adaptation.estimator.range_n_mm") or []
        nums = [r.number(n, "adaptation.estimator.range_n_mm") for n in items]
        if len(nums) == 2 and nums[0] is not None and nums[1] is not None:
            low, high = nums[0], nums[1]
        else:
            if len(items) != 2 and items:
                r.error(e["range_n_mm"], f"expected 2 numbers [k_min, k_max], got {len(items)}")
            r.quiet.add((*path, "range_n_mm"))
    inner: dict[str, Node] = {}
    if "inner_loop" in e:
        inner = r.section(e["inner_loop"], (*path, "inner_loop"), INNER_KEYS)
    return Estimator(
        inner_q=r.real(inner, (*path, "inner_loop", "q"), d.inner_q),
        inner_a=r.real(inner, (*path, "inner_loop", "a"), d.inner_a),
        inner_g=r.real(inner, (*path, "inner_loop", "g"), d.inner_g),
        window_periods=r.count(e, (*path, "window_periods"), d.window_periods),
        delay_periods=r.count(e, (*path, "delay_periods"), d.delay_periods),
        forgetting=r.real(e, (*path, "forgetting"), d.forgetting),
        min_step_m=r.real(e, (*path, "min_step_m"), d.min_step_m),
        min_force_n=r.real(e, (*path, "min_force_n"), d.min_force_n),
        initial_n_mm=r.real(e, (*path, "initial_n_mm"), d.initial_n_mm),
        k_min_n_mm=low,
        k_max_n_mm=high,
    )


def _bands(r: _SpecReader, node: Node | None) -> tuple[Band, ...]:
    path = (*BASE, "bands")
    if node is None:
        return ()
    r.where[path] = node
    items = r.sequence(node, "adaptation.bands (a list of {up_to_n_mm, scale})")
    if items is None:
        r.quiet.add(path)
        return ()
    out = []
    for i, item in enumerate(items):
        band_path = (*path, str(i))
        b = r.section(item, band_path, BAND_KEYS, ("scale",))
        up_to = r.real(b, (*band_path, "up_to_n_mm"), math.nan) if "up_to_n_mm" in b else None
        out.append(Band(scale=r.real(b, (*band_path, "scale")), up_to_n_mm=up_to))
    return tuple(out)
