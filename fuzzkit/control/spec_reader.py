"""Controller-spec YAML -> :class:`~fuzzkit.control.spec.ControllerSpec`, every problem located.

The format is documented in ``docs/controller.md``; :mod:`fuzzkit.control.spec_schema` is its
JSON Schema. The document is composed with the limits every fuzzkit YAML file obeys
(:func:`fuzzkit.formats.yaml_reader.compose_document`) and converted by hand: structural
problems (unknown keys, wrong types, an axis that does not exist) are reported where they are,
then the semantic checks of :func:`fuzzkit.control.spec.spec_problems` are mapped back to the
position of the value at fault. All problems are raised together as ``file:line:col: message``
in one :class:`~fuzzkit.errors.ControllerSpecError`.

Examples
--------
>>> spec = load_spec("docs/examples/controller.yaml")  # doctest: +SKIP
>>> spec.kind, spec.selection
('fuzzy-pi', (True, False, True))
"""

from __future__ import annotations

import hashlib
import math
import os
from pathlib import Path

from yaml.nodes import MappingNode, Node, ScalarNode, SequenceNode

from fuzzkit.control.adaptation_reader import read_adaptation
from fuzzkit.control.adaptation_spec import NONE
from fuzzkit.control.names import AXES, GAIN_KEYS, KINDS
from fuzzkit.control.spec import (
    EXACT,
    MAX_RESOLUTION,
    AxisSpec,
    ControllerSpec,
    Limits,
    Safety,
    SensorSpec,
    SpecPath,
    Surface,
    ToolSpec,
    spec_problems,
)
from fuzzkit.errors import ControllerSpecError, Location, Problem, RuleBaseError
from fuzzkit.fuzzy.model import RuleBase, Source
from fuzzkit.located_yaml import (
    NULL_TAG,
    DocumentKind,
    NodeReader,
    compose_document,
    read_document,
)

SPEC_DOCUMENT = DocumentKind(
    "controller spec",
    "controller specs",
    "expected a mapping with name, controller, period_s, axes, limits and safety",
    ControllerSpecError,
)

TOP_KEYS = (
    "name",
    "description",
    "controller",
    "rulebase",
    "period_s",
    "axes",
    "limits",
    "safety",
    "sensor",
    "adaptation",
    "surface",
    "inputs",
)
REQUIRED_KEYS = ("name", "controller", "period_s", "axes", "limits", "safety")
AXIS_KEYS = ("setpoint_n", "gains")
LIMIT_KEYS = ("correction_m", "step_m")
SAFETY_KEYS = ("limit_n", "engage", "spike_gate", "trip", "backoff", "watchdog")
ENGAGE_KEYS = ("threshold_n", "samples")
SPIKE_KEYS = ("threshold_n", "confirm")
TRIP_KEYS = ("samples",)
BACKOFF_KEYS = ("distance_m", "speed_m_s")
WATCHDOG_KEYS = ("periods",)
SENSOR_KEYS = ("tare", "tool", "lowpass_hz")
TARE_KEYS = ("samples",)
TOOL_KEYS = ("mass_kg", "com_m")
SURFACE_KEYS = ("method", "tolerance", "resolution")
#: Largest sample count a spec may give (tare, debounce, confirmation): 4000 s at 4 ms.
MAX_SAMPLES = 1_000_000


def is_null(node: Node) -> bool:
    """True for an explicit YAML null (``null``, ``~`` or nothing)."""
    return isinstance(node, ScalarNode) and node.tag == NULL_TAG


class _SpecReader(NodeReader):
    """Converts a composed spec document, recording where each logical path is.

    A value that cannot be read is reported where it is and replaced by a placeholder (NaN, a
    default); its path is *hidden*, so the semantic checks, which run on the whole spec anyway
    (every problem is reported at once), say nothing more about it.
    """

    def __init__(self, file: str, text: str, base_dir: Path | None) -> None:
        super().__init__(file, text.split("\n"))
        self.base_dir = base_dir
        self.where: dict[SpecPath, Node] = {}
        self.quiet: set[SpecPath] = set()  # nothing more about these or below them
        self.quiet_at: set[SpecPath] = set()  # nothing more about exactly these

    # ------------------------------------------------------------------ primitives

    def section(
        self,
        node: Node,
        path: SpecPath,
        allowed: tuple[str, ...],
        required: tuple[str, ...] = (),
    ) -> dict[str, Node]:
        """A mapping's values by key; unknown and missing keys reported and hidden."""
        what = ".".join(path) if path else "the controller spec"
        self.where[path] = node
        entries = self.mapping(node, f"{what} (a mapping)")
        if entries is None:
            self.quiet.add(path)
            return {}
        self.keys(entries, node, allowed, required, what)
        out: dict[str, Node] = {}
        for key, (_, value) in entries.items():
            if key in allowed:
                self.where[(*path, key)] = value
                out[key] = value
        self.quiet.update((*path, key) for key in required if key not in out)
        return out

    def real(self, entries: dict[str, Node], path: SpecPath, default: float = math.nan) -> float:
        """The number at ``path`` (non-finite ones pass: the semantic checks name them), or
        ``default`` when absent; NaN, hidden, when it is not a number."""
        node = entries.get(path[-1])
        if node is None:
            return default
        value = self.number(node, ".".join(path))
        if value is None:
            self.quiet.add(path)
            return math.nan
        return value

    def optional_real(
        self, entries: dict[str, Node], path: SpecPath, default: float | None
    ) -> float | None:
        """:meth:`real`, where an explicit null gives None."""
        node = entries.get(path[-1])
        if node is not None and is_null(node):
            return None
        return (
            self.real(entries, path, math.nan if default is None else default)
            if (node is not None or default is not None)
            else None
        )

    def count(self, entries: dict[str, Node], path: SpecPath, default: int) -> int:
        """The sample count at ``path`` (0 to :data:`MAX_SAMPLES`; the semantic checks say
        where 1 is the least), or ``default`` when absent or (reported, hidden) bad."""
        node = entries.get(path[-1])
        if node is None:
            return default
        value = self.integer(node, ".".join(path), 0, MAX_SAMPLES)
        if value is None:
            self.quiet.add(path)
            return default
        return value

    def word(self, entries: dict[str, Node], key: str, what: str, default: str) -> str:
        """The name at ``key``, or ``default`` when absent or (reported, hidden) bad."""
        node = entries.get(key)
        if node is None:
            return default
        value = self.name(node, what)
        if value is None:
            self.quiet.add((key,))
            return default
        return value

    # ------------------------------------------------------------------ sections

    def spec(self, root: Node, source: Source) -> ControllerSpec:
        top = self.section(root, (), TOP_KEYS, REQUIRED_KEYS)
        if "description" in top and self.text(top["description"], "description") is None:
            self.quiet.add(("description",))
        kind = self.word(top, "controller", "a controller kind (pi or fuzzy-pi)", "")
        if kind not in KINDS:
            if "controller" in top and ("controller",) not in self.quiet:
                self.error(
                    top["controller"], f"unknown controller {kind!r}; expected pi or fuzzy-pi"
                )
            self.quiet.update({("controller",), ("rulebase",)})
        rulebase, ref, target = self.rulebase(top.get("rulebase"), kind)
        axes = self.axes(top["axes"], kind) if "axes" in top else ()
        if kind not in KINDS:  # a placeholder the gains read fit, so their checks still run
            kind = "fuzzy-pi" if any(a.kx is not None for a in axes) else "pi"
        return ControllerSpec(
            name=self.word(top, "name", "a name (a C identifier)", "_"),
            kind=kind,
            period_s=self.real(top, ("period_s",)),
            axes=axes,
            limits=self.limits(top["limits"]) if "limits" in top else Limits(math.nan, math.nan),
            safety=self.safety(top["safety"]) if "safety" in top else Safety(math.nan),
            sensor=self.sensor(top["sensor"]) if "sensor" in top else SensorSpec(),
            rulebase=rulebase,
            rulebase_ref=ref,
            rulebase_source=target,
            adaptation=read_adaptation(self, top["adaptation"]) if "adaptation" in top else NONE,
            description=self.text(top["description"], "") or "" if "description" in top else "",
            source=source,
            surface=self.surface(top["surface"]) if "surface" in top else EXACT,
            inputs=self.inputs(top["inputs"]) if "inputs" in top else None,
        )

    def rulebase(
        self, node: Node | None, kind: str
    ) -> tuple[RuleBase | None, str | None, str | None]:
        """The rule base, the reference as written, and what ``registry.load`` takes for it."""
        if node is None:
            if kind == "fuzzy-pi":
                self.error(self.where[()], "missing required key 'rulebase' (fuzzy-pi needs one)")
            self.quiet.add(("rulebase",))
            return None, None, None
        ref = self.name(node, "a rule base (a shipped name or a path)")
        if ref is None or kind != "fuzzy-pi":
            if ref is not None and kind == "pi":
                self.error(node, "a pi controller takes no rule base; remove 'rulebase'")
            self.quiet.add(("rulebase",))
            return None, ref, None
        from fuzzkit.formats.registry import load, looks_like_path

        target: str | Path = ref
        if looks_like_path(ref):
            path = Path(ref)
            target = path if path.is_absolute() or self.base_dir is None else self.base_dir / path
        try:
            return load(target), ref, str(target)
        except RuleBaseError as exc:
            for problem in exc.problems:
                self.error(node, f"cannot load rule base {ref!r}: {problem}")
            self.quiet.add(("rulebase",))
            return None, ref, None

    def axes(self, node: Node, kind: str) -> tuple[AxisSpec, ...]:
        entries = self.section(node, ("axes",), AXES)
        out = [self.axis(axis, entries[axis], kind) for axis in AXES if axis in entries]
        if len(entries) != (len(node.value) if isinstance(node, MappingNode) else 0):
            self.quiet_at.add(("axes",))  # an unknown axis: "at least one axis" would mislead
        return tuple(a for a in out if a is not None)

    def axis(self, axis: str, node: Node, kind: str) -> AxisSpec | None:
        path = ("axes", axis)
        entries = self.section(node, path, AXIS_KEYS, AXIS_KEYS)
        allowed = GAIN_KEYS.get(kind, GAIN_KEYS["fuzzy-pi"])
        required = allowed if kind in KINDS else GAIN_KEYS["pi"]
        gains = (
            self.section(entries["gains"], (*path, "gains"), allowed, required)
            if ("gains" in entries)
            else {}
        )
        if "setpoint_n" not in entries or any(k not in gains for k in required):
            return None
        kx = self.real(gains, (*path, "gains", "kx")) if "kx" in gains else None
        return AxisSpec(
            axis,
            self.real(entries, (*path, "setpoint_n")),
            self.real(gains, (*path, "gains", "kp")),
            self.real(gains, (*path, "gains", "ki")),
            kx,
        )

    def limits(self, node: Node) -> Limits:
        entries = self.section(node, ("limits",), LIMIT_KEYS, LIMIT_KEYS)
        return Limits(
            self.real(entries, ("limits", "correction_m")), self.real(entries, ("limits", "step_m"))
        )

    def safety(self, node: Node) -> Safety:
        top = self.section(node, ("safety",), SAFETY_KEYS, ("limit_n",))
        d = Safety(math.nan)  # the defaults

        def sub(key: str, allowed: tuple[str, ...]) -> dict[str, Node]:
            return self.section(top[key], ("safety", key), allowed) if key in top else {}

        engage = sub("engage", ENGAGE_KEYS)
        spike = sub("spike_gate", SPIKE_KEYS)
        trip = sub("trip", TRIP_KEYS)
        backoff = sub("backoff", BACKOFF_KEYS)
        watchdog = sub("watchdog", WATCHDOG_KEYS)
        return Safety(
            limit_n=self.real(top, ("safety", "limit_n")),
            engage_threshold_n=self.optional_real(
                engage, ("safety", "engage", "threshold_n"), d.engage_threshold_n
            ),
            engage_samples=self.count(engage, ("safety", "engage", "samples"), d.engage_samples),
            spike_gate_n=self.optional_real(spike, ("safety", "spike_gate", "threshold_n"), None),
            spike_confirm=self.count(spike, ("safety", "spike_gate", "confirm"), d.spike_confirm),
            trip_samples=self.count(trip, ("safety", "trip", "samples"), d.trip_samples),
            backoff_m=self.real(backoff, ("safety", "backoff", "distance_m"), d.backoff_m),
            backoff_speed_m_s=self.real(
                backoff, ("safety", "backoff", "speed_m_s"), d.backoff_speed_m_s
            ),
            watchdog_periods=self.count(
                watchdog, ("safety", "watchdog", "periods"), d.watchdog_periods
            ),
        )

    def sensor(self, node: Node) -> SensorSpec:
        entries = self.section(node, ("sensor",), SENSOR_KEYS)
        tare = {}
        if "tare" in entries:
            tare = self.section(entries["tare"], ("sensor", "tare"), TARE_KEYS, TARE_KEYS)
        tool = None
        if "tool" in entries and not is_null(entries["tool"]):
            tool = self.tool(entries["tool"])
        return SensorSpec(
            tare_samples=self.count(tare, ("sensor", "tare", "samples"), 0),
            tool=tool,
            lowpass_hz=self.optional_real(entries, ("sensor", "lowpass_hz"), None),
        )

    def tool(self, node: Node) -> ToolSpec:
        path = ("sensor", "tool")
        entries = self.section(node, path, TOOL_KEYS, ("mass_kg",))
        com: tuple[float, float, float] = (0.0, 0.0, 0.0)
        if "com_m" in entries:
            items = self.sequence(entries["com_m"], "sensor.tool.com_m") or []
            nums = [self.number(n, "sensor.tool.com_m") for n in items]
            if len(items) != 3 and isinstance(entries["com_m"], SequenceNode):
                self.error(
                    entries["com_m"], f"expected 3 numbers (x, y, z) for com_m, got {len(items)}"
                )
            if len(nums) == 3 and all(v is not None for v in nums):
                com = (float(nums[0] or 0.0), float(nums[1] or 0.0), float(nums[2] or 0.0))
            else:
                self.quiet.add((*path, "com_m"))
        return ToolSpec(self.real(entries, (*path, "mass_kg")), com)

    def surface(self, node: Node) -> Surface:
        """``surface: exact`` (or ``table``), or ``{method, tolerance | resolution}``."""
        path: SpecPath = ("surface",)
        self.where[path] = node
        if not isinstance(node, MappingNode):
            method = self.name(node, "a surface method (exact or table) or a mapping")
            if method is None:
                self.quiet.add(path)
                return EXACT
            self.where[(*path, "method")] = node
            return Surface(method)
        entries = self.section(node, path, SURFACE_KEYS, ("method",))
        method = "exact"
        if "method" in entries:
            method = self.name(entries["method"], "a surface method (exact or table)") or ""
            if not method:
                self.quiet.add(path)
                method = "exact"
        tolerance = self.optional_real(entries, (*path, "tolerance"), None)
        resolution = None
        if "resolution" in entries:
            resolution = self.integer(
                entries["resolution"], "surface.resolution", 2, MAX_RESOLUTION
            )
            if resolution is None:
                self.quiet.add((*path, "resolution"))
                self.quiet_at.add(path)
                resolution = 2
        return Surface(method, tolerance, resolution)

    def inputs(self, node: Node) -> tuple[str, str] | None:
        """``inputs: [error, change]``: the rule base's input names in role order."""
        self.where[("inputs",)] = node
        items = self.sequence(node, "inputs: [error input, change input]")
        if items is not None and len(items) != 2:
            self.error(
                node, f"expected 2 input names (the error's, then its change's), got {len(items)}"
            )
            items = None
        names = [self.name(n, "an input name") for n in items or []]
        if items is None or None in names:
            self.quiet.add(("inputs",))
            return None
        return (str(names[0]), str(names[1]))

    # ------------------------------------------------------------------ semantics

    def locate(self, path: SpecPath) -> Node:
        for n in range(len(path), -1, -1):
            node = self.where.get(path[:n])
            if node is not None:
                return node
        return self.where[()]

    def is_hidden(self, path: SpecPath) -> bool:
        return path in self.quiet_at or any(path[: len(h)] == h for h in self.quiet)


def read_spec_node(
    root: Node, source: Source, text: str, base_dir: str | Path | None = None
) -> tuple[ControllerSpec | None, list[Problem]]:
    """A spec from a composed node (a whole document, or a scenario's embedded ``controller``
    mapping) and every problem found, located in ``source.path``; the spec is None when there
    is a problem."""
    reader = _SpecReader(source.path, text, None if base_dir is None else Path(base_dir))
    spec = reader.spec(root, source)
    for path, message in spec_problems(spec):
        if not reader.is_hidden(path):
            reader.error(reader.locate(path), message)
    problems = list(dict.fromkeys(reader.problems))
    problems.sort(key=lambda p: (p.location.line, p.location.col))
    return (None if problems else spec), problems


def loads_spec(
    text: str, source: str = "<string>", base_dir: str | Path | None = None
) -> ControllerSpec:
    """Parse controller-spec YAML ``text``; ``source`` names it in messages.

    A rule base given as a relative path is read relative to ``base_dir`` (the spec file's
    folder for :func:`load_spec`; the working directory when None).

    Raises
    ------
    ControllerSpecError
        Listing every problem as ``source:line:col: message``, sorted by position.
    """
    root = compose_document(text, source, SPEC_DOCUMENT)
    digest = hashlib.sha256(text.encode("utf-8")).hexdigest()
    spec, problems = read_spec_node(root, Source(source, digest), text, base_dir)
    if spec is None:
        raise ControllerSpecError(problems or [Problem(Location(source), "not a valid spec")])
    return spec


def load_spec(path: str | os.PathLike[str]) -> ControllerSpec:
    """Read and parse a controller-spec YAML file (see :func:`loads_spec`)."""
    p = Path(path)
    return loads_spec(read_document(p, SPEC_DOCUMENT), str(path), p.parent)
