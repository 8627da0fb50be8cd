"""Scenario files: an experiment (world, path, force-control task, latency, fault) as YAML.

The shipped experiments E1-E3 are such files (``fuzzkit/studies/scenarios/*.yaml``); a user's
own task is one more. Loading is as strict as for rule bases (the same composing, limits and
``file:line:col`` problems, all reported together, :mod:`fuzzkit.located_yaml`). The
format is documented in ``docs/simulation.md`` (Scenario files); :func:`json_schema` is its
JSON Schema.
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
from importlib import resources
from pathlib import Path
from typing import Any

from yaml.nodes import MappingNode, Node, ScalarNode

from fuzzkit.control.names import AXES
from fuzzkit.control.spec import ControllerSpec
from fuzzkit.errors import ConfigError, ControllerSpecError, Location, Problem, ScenarioError
from fuzzkit.fuzzy.model import Source
from fuzzkit.located_yaml import (
    NULL_TAG,
    DocumentKind,
    NodeReader,
    compose_document,
    read_document,
)
from fuzzkit.loop.faults import FAULTS
from fuzzkit.loop.task import Experiment, with_spec
from fuzzkit.plants.contact import ContactModel, SensorModel, ToolModel
from fuzzkit.plants.contract import Scenario
from fuzzkit.plants.environment import Box, EnvObject, RoughSurface, Table, Waypoint
from fuzzkit.units import MAX_DURATION_S, MAX_LATENCY_PERIODS, parse_stiffness

SCENARIO_DOCUMENT = DocumentKind(
    "scenario",
    "scenarios",
    "expected a mapping with name, duration_s, path, objects and force_control",
    ScenarioError,
)

TOP_KEYS = (
    "name",
    "title",
    "description",
    "duration_s",
    "period_s",
    "tool",
    "path",
    "objects",
    "contact",
    "sensor",
    "force_control",
    "safety_limit_n",
    "engage",
    "steady_window_s",
    "latency_periods",
    "fault",
    "controller",
)
REQUIRED_KEYS = ("name", "duration_s", "path", "objects", "force_control", "safety_limit_n")
#: What a scenario with a controller spec leaves to the spec (the spec holds them).
SPEC_KEYS = ("force_control", "safety_limit_n")
SPEC_ENGAGE_KEYS = ("threshold_n", "samples")
WAYPOINT_KEYS = ("t_s", "x", "y", "z", "tilt_deg")
ENGAGE_KEYS = ("threshold_n", "samples", "hold_path")
LATENCY_KEYS = ("sensor", "command")
#: Environment objects by their key in ``objects``; RoughSurface also takes ``tilt_deg``.
OBJECT_KINDS: dict[str, type[Any]] = {"table": Table, "box": Box, "rough_surface": RoughSurface}
#: Keys of the plain sections, each a dataclass read field by field.
SECTIONS: dict[str, type[Any]] = {"tool": ToolModel, "contact": ContactModel, "sensor": SensorModel}
SHIPPED = ("E1", "E2", "E3")

#: Limits that keep a scenario a simulation this machine can run (documented in
#: docs/simulation.md): simulated time, control period, periods in one run, delays.
MIN_PERIOD_S = 1e-4
MAX_PERIOD_S = 0.1
MAX_STEPS = 1_000_000


#: Fields whose name ends so are stiffnesses in N/m that also take a value with its unit.
STIFFNESS_SUFFIX = "stiffness_n_per_m"


def _spelled_out(node: Node) -> bool:
    """A plain string scalar holding letters (a number with its unit, ``10 N/mm``)."""
    return (
        isinstance(node, ScalarNode)
        and node.style is None
        and any(c.isalpha() for c in node.value)
        and any(c.isdigit() for c in node.value)
    )


class _ScenarioReader(NodeReader):
    """Converts a composed scenario document into an :class:`Experiment`."""

    def __init__(self, file: str, text: str, base_dir: Path | None) -> None:
        super().__init__(file, text.split("\n"))
        self.source_text = text
        self.base_dir = base_dir

    def controller(self, node: Node) -> ControllerSpec | None:
        """The scenario's controller: a spec file's path (relative to the scenario) or an
        embedded spec mapping; its problems join the scenario's."""
        from fuzzkit.control.spec_reader import load_spec, read_spec_node

        if isinstance(node, MappingNode):
            digest = hashlib.sha256(self.source_text.encode("utf-8")).hexdigest()
            spec, problems = read_spec_node(
                node, Source(self.file, digest), self.source_text, self.base_dir
            )
            self.problems.extend(problems)
            return spec
        ref = self.name(node, "a controller spec (a path, or the spec as a mapping)")
        if ref is None:
            return None
        path = Path(ref)
        if not path.is_absolute() and self.base_dir is not None:
            path = self.base_dir / path
        try:
            return load_spec(path)
        except ControllerSpecError as exc:
            self.error(node, f"controller spec {ref!r} is not valid (its problems follow)")
            self.problems.extend(exc.problems)
            return None

    def positive(
        self, node: Node, what: str, allow_zero: bool = False, high: float = math.inf
    ) -> float | None:
        v = self.number(node, what)
        if v is None:
            return None
        if not math.isfinite(v) or v < 0.0 or (v == 0.0 and not allow_zero) or v > high:
            bound = ">= 0" if allow_zero else "> 0"
            upper = f" and <= {high:g}" if math.isfinite(high) else ""
            self.error(node, f"{what} must be a finite number {bound}{upper} (got {v:g})")
            return None
        return v

    def record(self, cls: type[Any], node: Node, what: str, extra: tuple[str, ...] = ()) -> Any:
        """A dataclass of ``cls`` from a mapping keyed by its field names (defaults apply)."""
        entries = self.mapping(node, what)
        if entries is None:
            return None
        fields = {f.name: f for f in dataclasses.fields(cls)}
        required = [
            n
            for n, f in fields.items()
            if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
        ]
        if "tilt_deg" in extra and "tilt_deg" in entries:
            required = [r for r in required if r != "tilt_rad"]
        self.keys(entries, node, tuple(fields) + extra, required, what)
        values: dict[str, Any] = {}
        ok = True
        for key, (_, vnode) in entries.items():
            if key == "tilt_deg" and key in extra:
                if "tilt_rad" in entries:
                    self.error(vnode, f"{what}: give tilt_deg or tilt_rad, not both")
                    ok = False
                    continue
                deg = self.finite(vnode, f"{what} tilt_deg")
                ok &= deg is not None
                if deg is not None:
                    values["tilt_rad"] = math.radians(deg)
                continue
            f = fields.get(key)
            if f is None:
                ok = False
                continue
            value = self._field(f, vnode, f"{what} {key}")
            ok &= value is not None
            values[key] = value
        if not ok or any(r not in entries for r in required):
            return None
        try:
            return cls(**values)
        except (ConfigError, ValueError) as exc:
            self.error(node, f"{what}: {exc}")
            return None

    def _field(self, f: dataclasses.Field[Any], node: Node, what: str) -> Any:
        kind = str(f.type)
        if kind == "str":
            return self.name(node, f"a name for {what}")
        if kind == "int":
            return self.integer(node, what)
        if kind.startswith("tuple"):
            items = self.sequence(node, what)
            if items is None:
                return None
            if len(items) != 3:
                self.error(node, f"expected 3 numbers (x, y, z) for {what}, got {len(items)}")
                return None
            nums = [self.finite(n, what) for n in items]
            return None if any(v is None for v in nums) else tuple(nums)
        if f.name.endswith(STIFFNESS_SUFFIX) and _spelled_out(node):
            try:  # the key's unit is N/m; another is accepted spelled out ("10 N/mm")
                return parse_stiffness(node.value, "N/m")
            except ConfigError as exc:
                self.error(node, f"{what}: {exc}")
                return None
        return self.finite(node, what)

    def path(self, node: Node) -> tuple[Waypoint, ...] | None:
        items = self.sequence(node, "path")
        if items is None:
            return None
        if not items:
            self.error(node, "path needs at least one waypoint")
            return None
        out: list[Waypoint] = []
        for k, item in enumerate(items):
            entries = self.mapping(item, f"path[{k}] (a mapping with t_s, x, z)")
            if entries is None:
                continue
            self.keys(entries, item, WAYPOINT_KEYS, ("t_s", "x", "z"), f"path[{k}]")
            vals = {key: self.finite(v, f"path[{k}] {key}") for key, (_, v) in entries.items()}
            if any(vals.get(key) is None for key in ("t_s", "x", "z")) or len(vals) != len(
                [key for key in vals if key in WAYPOINT_KEYS]
            ):
                continue
            t = vals["t_s"]
            if out and t is not None and t < out[-1].t_s:
                before = out[-1].t_s
                self.error(
                    entries["t_s"][1],
                    f"path[{k}]: time {t:g} s is before the previous {before:g} s",
                )
                continue
            tilt = math.radians(vals.get("tilt_deg") or 0.0)
            out.append(Waypoint(t, vals["x"], vals.get("y") or 0.0, vals["z"], tilt))  # type: ignore[arg-type]
        return tuple(out) if len(out) == len(items) else None

    def objects(self, node: Node) -> tuple[EnvObject, ...] | None:
        items = self.sequence(node, "objects")
        if items is None:
            return None
        out: list[EnvObject] = []
        for k, item in enumerate(items):
            entries = self.mapping(item, f"objects[{k}] (one of {', '.join(OBJECT_KINDS)})")
            if entries is None:
                continue
            if len(entries) != 1:
                self.error(item, f"objects[{k}]: expected one key ({', '.join(OBJECT_KINDS)})")
                continue
            ((kind, (_, vnode)),) = entries.items()
            cls = OBJECT_KINDS.get(kind)
            if cls is None:
                self.keys(entries, item, tuple(OBJECT_KINDS), (), f"objects[{k}]")
                continue
            extra = ("tilt_deg",) if cls is RoughSurface else ()
            obj = self.record(cls, vnode, f"objects[{k}] {kind}", extra)
            if obj is not None:
                out.append(obj)
        return tuple(out) if len(out) == len(items) else None

    def force_control(
        self, node: Node
    ) -> tuple[tuple[float, float, float], tuple[bool, bool, bool]] | None:
        entries = self.mapping(node, "force_control (set point in N per task axis x, y, z)")
        if entries is None:
            return None
        self.keys(entries, node, AXES, (), "force_control")
        if not entries:
            self.error(node, "force_control needs at least one axis (x, y or z)")
            return None
        setpoints = [0.0, 0.0, 0.0]
        selection = [False, False, False]
        for axis, (_, vnode) in entries.items():
            if axis not in AXES:
                return None
            value = self.finite(vnode, f"the {axis} set point")
            if value is None:
                return None
            i = AXES.index(axis)
            setpoints[i], selection[i] = value, True
        x, y, z = setpoints
        sx, sy, sz = selection
        return (x, y, z), (sx, sy, sz)

    def engage(self, node: Node) -> tuple[float | None, int, bool] | None:
        entries = self.mapping(node, "engage")
        if entries is None:
            return None
        self.keys(entries, node, ENGAGE_KEYS, (), "engage")
        threshold: float | None = 1.0
        samples, hold = 3, False
        ok = True
        if "threshold_n" in entries:
            tnode = entries["threshold_n"][1]
            if isinstance(tnode, ScalarNode) and tnode.tag == NULL_TAG:
                threshold = None  # active from the start
            else:
                threshold = self.positive(tnode, "engage threshold_n", allow_zero=True)
                ok &= threshold is not None
        if "samples" in entries:
            s = self.integer(entries["samples"][1], "engage samples", 1, MAX_STEPS)
            ok &= s is not None
            samples = s or samples
        if "hold_path" in entries:
            h = self.boolean(entries["hold_path"][1], "engage hold_path")
            ok &= h is not None
            hold = bool(h)
        return (threshold, samples, hold) if ok else None

    def latency(self, node: Node) -> tuple[int, int] | None:
        entries = self.mapping(node, "latency_periods (sensor and command delays in periods)")
        if entries is None:
            return None
        self.keys(entries, node, LATENCY_KEYS, LATENCY_KEYS, "latency_periods")
        vals = [
            self.integer(entries[k][1], f"latency_periods {k}", maximum=MAX_LATENCY_PERIODS)
            if k in entries
            else None
            for k in LATENCY_KEYS
        ]
        if vals[0] is None or vals[1] is None:
            return None
        return vals[0], vals[1]

    def time_limits(self, values: dict[str, Any], top: dict[str, tuple[Node, Node]]) -> None:
        """Refuse a period below :data:`MIN_PERIOD_S` or more than :data:`MAX_STEPS` periods."""
        period, duration = values.get("period_s", 0.004), values.get("duration_s")
        if period is None or duration is None:
            return
        if period < MIN_PERIOD_S:
            self.error(
                top["period_s"][1], f"period_s must be >= {MIN_PERIOD_S:g} s (got {period:g})"
            )
            values["period_s"] = None
        elif duration / period > MAX_STEPS:
            self.error(
                top["duration_s"][1],
                f"duration_s / period_s is {duration / period:.3g} periods; a run is limited "
                f"to {MAX_STEPS} periods (shorten duration_s or lengthen period_s)",
            )
            values["duration_s"] = None

    def experiment(self, root: Node) -> Experiment | None:
        top = self.mapping(root, "a scenario (a mapping)")
        if top is None:
            return None
        with_spec_keys = "controller" in top
        required = tuple(k for k in REQUIRED_KEYS if not (with_spec_keys and k in SPEC_KEYS))
        self.keys(top, root, TOP_KEYS, required, "the scenario")
        spec = self.controller(top["controller"][1]) if with_spec_keys else None
        if with_spec_keys:
            self.spec_owned(top)

        def get(key: str) -> Node | None:
            return top[key][1] if key in top else None

        values: dict[str, Any] = {}
        for key in ("name", "title", "description"):
            node = get(key)
            if node is not None:
                values[key] = self.text(node, key)
        for key, high in (
            ("duration_s", MAX_DURATION_S),
            ("period_s", MAX_PERIOD_S),
            ("safety_limit_n", math.inf),
            ("steady_window_s", MAX_DURATION_S),
        ):
            node = get(key)
            if node is not None:
                values[key] = self.positive(node, key, high=high)
        self.time_limits(values, top)
        sections = {}
        for key, cls in SECTIONS.items():
            node = get(key)
            sections[key] = cls() if node is None else self.record(cls, node, key)
        path = objects = fc = latency = None
        engage: tuple[float | None, int, bool] | None = (1.0, 3, False)
        fault = "none"
        for key, (_, node) in top.items():
            if key == "path":
                path = self.path(node)
            elif key == "objects":
                objects = self.objects(node)
            elif key == "force_control":
                fc = self.force_control(node)
            elif key == "engage":
                engage = self.engage(node)
            elif key == "latency_periods":
                latency = self.latency(node)
            elif key == "fault":
                name = self.name(node, "a fault kind")
                if name is not None and name not in FAULTS:
                    self.error(node, f"unknown fault {name!r}; expected one of {', '.join(FAULTS)}")
                fault = name or fault
        if spec is not None:
            fc = (spec.setpoints, spec.selection)
            values["safety_limit_n"] = spec.safety.limit_n
            if "period_s" not in values:
                values["period_s"] = spec.period_s
            elif values["period_s"] != spec.period_s:
                self.error(
                    top["period_s"][1],
                    f"period_s {values['period_s']:g} differs from the controller spec's "
                    f"{spec.period_s:g}; give one period (or leave it to the spec)",
                )
        if path is None or objects is None or fc is None or engage is None:
            return None
        if self.problems or any(v is None for v in (*values.values(), *sections.values())):
            return None
        try:
            scn = Scenario(
                name=values["name"],
                path=path,
                objects=objects,
                duration_s=values["duration_s"],
                contact=sections["contact"],
                sensor=sections["sensor"],
                tool=sections["tool"],
                period_s=values.get("period_s", 0.004),
                description=values.get("description", ""),
            )
        except ConfigError as exc:
            self.error(root, str(exc))
            return None
        extra: dict[str, Any] = {}
        if latency is not None:
            extra["latency_periods"] = latency
        if "steady_window_s" in values:
            extra["steady_window_s"] = values["steady_window_s"]
        exp = Experiment(
            name=values["name"],
            title=values.get("title", values.get("description", values["name"])),
            scenario=scn,
            setpoints=fc[0],
            selection=fc[1],
            force_limit_n=values["safety_limit_n"],
            engage_threshold_n=engage[0],
            engage_samples=engage[1],
            hold_path_on_contact=engage[2],
            fault=fault,
            **extra,
        )
        return exp if spec is None else with_spec(exp, spec)

    def spec_owned(self, top: dict[str, tuple[Node, Node]]) -> None:
        """With a controller spec, the task's axes, set points, safety limit and engagement are
        the spec's: giving them in the scenario too is an error (one source of truth)."""
        for key in SPEC_KEYS:
            if key in top:
                self.error(
                    top[key][0],
                    f"{key} is the controller spec's (its axes and safety); remove it here",
                )
        if "engage" in top and isinstance(top["engage"][1], MappingNode):
            for knode, _ in top["engage"][1].value:
                if isinstance(knode, ScalarNode) and knode.value in SPEC_ENGAGE_KEYS:
                    self.error(
                        knode,
                        f"engage {knode.value} is the controller spec's (safety.engage); "
                        "remove it here (hold_path stays)",
                    )


def loads_scenario(
    text: str, source: str = "<string>", base_dir: str | Path | None = None
) -> Experiment:
    """Parse scenario YAML ``text``; ``source`` names it in messages. A controller spec given
    by a relative path is read relative to ``base_dir`` (the working directory when None).

    Raises
    ------
    ScenarioError
        Listing every problem as ``source:line:col: message``, sorted by position.
    """
    root = compose_document(text, source, SCENARIO_DOCUMENT)
    reader = _ScenarioReader(source, text, None if base_dir is None else Path(base_dir))
    exp = reader.experiment(root)
    if reader.problems or exp is None:
        problems = list(dict.fromkeys(reader.problems)) or [
            Problem(Location(source), "not a valid scenario")
        ]
        problems.sort(key=lambda p: (p.location.line, p.location.col))
        raise ScenarioError(problems)
    return exp


def load_scenario(path: str | Path) -> Experiment:
    """Read and parse a scenario YAML file (see :func:`loads_scenario`)."""
    return loads_scenario(read_document(path, SCENARIO_DOCUMENT), str(path), Path(path).parent)


def shipped_scenario_text(name: str) -> str:
    """The text of a shipped scenario (E1, E2, E3)."""
    return resources.files("fuzzkit.studies.scenarios").joinpath(f"{name}.yaml").read_text("utf-8")


def json_schema() -> dict[str, Any]:
    """A JSON Schema (draft 2020-12) of the scenario format, for editors and linters.

    Structural only; the loader also checks values (positive durations, waypoint order ...).
    """
    from fuzzkit.control.spec_schema import json_schema as spec_schema

    def controller_schema() -> dict[str, Any]:
        embedded = spec_schema()
        embedded.pop("$schema")
        return embedded

    number = {"type": "number"}

    def record(cls: type[Any], extra: dict[str, Any] | None = None) -> dict[str, Any]:
        props: dict[str, Any] = {}
        required = []
        for f in dataclasses.fields(cls):
            t = str(f.type)
            if t == "str":
                props[f.name] = {"type": "string"}
            elif t == "int":
                props[f.name] = {"type": "integer", "minimum": 0}
            elif t.startswith("tuple"):
                props[f.name] = {"type": "array", "items": number, "minItems": 3, "maxItems": 3}
            elif f.name.endswith(STIFFNESS_SUFFIX):
                props[f.name] = {
                    "oneOf": [
                        number,
                        {"type": "string", "pattern": r"^\s*[0-9.eE+-]+\s*(N/mm|N/m|kN/m)\s*$"},
                    ],
                    "description": "N/m, or a number with its unit (10 N/mm, 1e4 N/m)",
                }
            else:
                props[f.name] = number
            if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
                required.append(f.name)
        props.update(extra or {})
        return {
            "type": "object",
            "properties": props,
            "required": required,
            "additionalProperties": False,
        }

    rough = record(RoughSurface, {"tilt_deg": number})
    rough["required"] = [r for r in rough["required"] if r != "tilt_rad"]
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": "fuzzkit scenario",
        "type": "object",
        "required": [k for k in REQUIRED_KEYS if k not in SPEC_KEYS],
        "additionalProperties": False,
        # without a controller spec, the scenario names its axes and safety limit itself
        "if": {"not": {"required": ["controller"]}},
        "then": {"required": list(SPEC_KEYS)},
        "else": {"not": {"anyOf": [{"required": [k]} for k in SPEC_KEYS]}},
        "properties": {
            "controller": {
                "oneOf": [
                    {"type": "string", "description": "a controller spec file (relative path)"},
                    controller_schema(),
                ]
            },
            "name": {"type": "string"},
            "title": {"type": "string"},
            "description": {"type": "string"},
            "duration_s": {"type": "number", "exclusiveMinimum": 0},
            "period_s": {"type": "number", "exclusiveMinimum": 0},
            "safety_limit_n": {"type": "number", "exclusiveMinimum": 0},
            "steady_window_s": {"type": "number", "exclusiveMinimum": 0},
            "tool": record(ToolModel),
            "contact": record(ContactModel),
            "sensor": record(SensorModel),
            "path": {
                "type": "array",
                "minItems": 1,
                "items": {
                    "type": "object",
                    "properties": {k: number for k in WAYPOINT_KEYS},
                    "required": ["t_s", "x", "z"],
                    "additionalProperties": False,
                },
            },
            "objects": {
                "type": "array",
                "items": {
                    "oneOf": [
                        {
                            "type": "object",
                            "properties": {"table": record(Table)},
                            "required": ["table"],
                            "additionalProperties": False,
                        },
                        {
                            "type": "object",
                            "properties": {"box": record(Box)},
                            "required": ["box"],
                            "additionalProperties": False,
                        },
                        {
                            "type": "object",
                            "properties": {"rough_surface": rough},
                            "required": ["rough_surface"],
                            "additionalProperties": False,
                        },
                    ]
                },
            },
            "force_control": {
                "type": "object",
                "properties": {a: number for a in AXES},
                "minProperties": 1,
                "additionalProperties": False,
            },
            "engage": {
                "type": "object",
                "properties": {
                    "threshold_n": {"type": ["number", "null"], "minimum": 0},
                    "samples": {"type": "integer", "minimum": 1},
                    "hold_path": {"type": "boolean"},
                },
                "additionalProperties": False,
            },
            "latency_periods": {
                "type": "object",
                "properties": {k: {"type": "integer", "minimum": 0} for k in LATENCY_KEYS},
                "required": list(LATENCY_KEYS),
                "additionalProperties": False,
            },
            "fault": {"enum": list(FAULTS)},
        },
    }
