"""Gains files: the one format, reader and writer for controller gains and their provenance.

Used by ``fuzzkit simulate --gains``, ``fuzzkit compare --gains``, ``fuzzkit compile --gains``
(read) and ``fuzzkit tune`` / ``fuzzkit report`` (write).

Format (YAML)
-------------
Top-level keys are controller names (``pi``, ``fuzzy-pi``); each value is either the gains
themselves or a mapping with ``gains`` and an optional free-form ``provenance``::

    fuzzy-pi:
      gains: {kp: 0.31, ki: 0.062, kx: 0.00018, u_min: -0.05, u_max: 0.05}
      provenance: {tool: fuzzkit tune, experiments: [E1], stiffness_n_per_mm: [5, 10, 20],
                   cost: 0.0123, default_cost: 0.0151, seed: 0, budget: 120}
    pi:
      kp: 4.0e-5
      ki: 1.0e-5

A file holding only gains (``kp: 4e-5`` ...) applies to whichever controller reads it.

Gain keys: PI ``kp``, ``ki`` (m/N, >= 0); fuzzy-PI ``kp`` (scales de, 1/N), ``ki`` (scales e,
1/N), ``kx`` (m per step), all > 0; both accept ``u_min <= 0 <= u_max`` (m) and
``rate_limit > 0`` (m per step). Every problem is reported at once as ``file:line: what (expected
X, got Y)`` in one :class:`~fuzzkit.errors.ConfigError`.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from fuzzkit.errors import ConfigError

#: Controller names a gains file may hold, in file order.
CONTROLLERS = ("pi", "fuzzy-pi")

#: The gain keys each controller accepts.
GAIN_KEYS: dict[str, tuple[str, ...]] = {
    "pi": ("kp", "ki", "u_min", "u_max", "rate_limit"),
    "fuzzy-pi": ("kp", "ki", "kx", "u_min", "u_max", "rate_limit"),
}

#: Every gain key of any controller (a flat file may hold any of them).
_ALL_KEYS = tuple(dict.fromkeys(k for keys in GAIN_KEYS.values() for k in keys))

#: A decimal number in exponent notation (what YAML 1.1 fails to read as a float).
_FLOAT = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?")

#: Keys of a structured entry (``{gains: ..., provenance: ...}``).
_ENTRY_KEYS = ("gains", "provenance")


@dataclass(frozen=True, slots=True)
class GainsEntry:
    """The gains of one controller and where they came from (free-form, for humans)."""

    controller: str | None  # None: a flat file that applies to any controller
    gains: dict[str, float]
    provenance: dict[str, Any] = field(default_factory=dict)


def _line_index(node: Any) -> dict[tuple[str, ...], int]:
    """Map every key path of a composed YAML mapping tree to its 1-based line."""
    import yaml

    out: dict[tuple[str, ...], int] = {}

    def walk(n: Any, path: tuple[str, ...]) -> None:
        if isinstance(n, yaml.MappingNode):
            for k, v in n.value:
                key = (*path, str(k.value))
                out[key] = k.start_mark.line + 1
                walk(v, key)

    if node is not None:
        out[()] = node.start_mark.line + 1
        walk(node, ())
    return out


def _number(val: Any) -> Any:
    """``val``, or the float a string like ``1e-4`` spells.

    YAML 1.1 (PyYAML) reads ``1e-4`` without a decimal point as a *string*; engineers write
    gains that way, so such strings are accepted as numbers (not nan/inf spellings).
    """
    if isinstance(val, str) and _FLOAT.fullmatch(val.strip()):
        return float(val)
    return val


def _check_gains(
    controller: str | None,
    data: Any,
    where: str,
    lines: dict[tuple[str, ...], int],
    path: tuple[str, ...],
    problems: list[str],
) -> dict[str, float]:
    """Validate one gains mapping; append located problems; return the valid gains."""

    def at(*keys: str) -> str:
        line = lines.get((*path, *keys)) or lines.get(path) or 0
        return f"{where}:{line}" if line else where

    if not isinstance(data, dict):
        problems.append(f"{at()}: gains must be a mapping (got {type(data).__name__})")
        return {}
    allowed = GAIN_KEYS[controller] if controller else _ALL_KEYS
    out: dict[str, float] = {}
    for key, val in data.items():
        k = str(key)
        val = _number(val)
        if k not in allowed:
            problems.append(
                f"{at(k)}: unknown gain {k!r}"
                + (f" for {controller}" if controller else "")
                + f" (expected one of {', '.join(allowed)})"
            )
        elif isinstance(val, bool) or not isinstance(val, int | float) or not math.isfinite(val):
            problems.append(f"{at(k)}: gain {k} must be a finite number (got {val!r})")
        else:
            out[k] = float(val)
    # Sign and order checks the controllers would make, but located in the file.
    strict = controller == "fuzzy-pi"
    for k in ("kp", "ki", "kx"):
        if k in out and (out[k] <= 0.0 if strict else out[k] < 0.0):
            want = "> 0" if strict else ">= 0"
            problems.append(f"{at(k)}: gain {k} must be {want} (got {out[k]!r})")
    if "u_min" in out and out["u_min"] > 0.0:
        problems.append(f"{at('u_min')}: u_min must be <= 0 (got {out['u_min']!r})")
    if "u_max" in out and out["u_max"] < 0.0:
        problems.append(f"{at('u_max')}: u_max must be >= 0 (got {out['u_max']!r})")
    if "rate_limit" in out and out["rate_limit"] <= 0.0:
        problems.append(f"{at('rate_limit')}: rate_limit must be > 0 (got {out['rate_limit']!r})")
    return out


def parse_gains(text: str, where: str = "<gains>") -> dict[str | None, GainsEntry]:
    """Parse a gains file's text into entries keyed by controller (None: a flat file).

    Parameters
    ----------
    text : the YAML text.
    where : the file name used in messages.

    Returns
    -------
    ``{controller: GainsEntry}``; a flat file gives ``{None: entry}``.

    Raises
    ------
    ConfigError
        Not YAML, not a mapping, unknown controllers or keys, non-finite or out-of-range gains:
        every problem, each as ``file:line: ...``.
    """
    import yaml

    try:
        node = yaml.compose(text, Loader=yaml.SafeLoader)
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        loc = f"{where}:{mark.line + 1}" if mark is not None else where
        problem = getattr(exc, "problem", None)
        raise ConfigError(f"{loc}: not valid YAML" + (f" ({problem})" if problem else "")) from exc
    if not isinstance(data, dict):
        got = "an empty file" if data is None else type(data).__name__
        raise ConfigError(f"{where}: expected a mapping of gains, got {got}")
    lines = _line_index(node)
    problems: list[str] = []
    entries: dict[str | None, GainsEntry] = {}
    keys = [str(k) for k in data]
    if not any(k in CONTROLLERS for k in keys):
        gains = _check_gains(None, data, where, lines, (), problems)
        entries[None] = GainsEntry(None, gains)
    else:
        unknown = [k for k in keys if k not in CONTROLLERS]
        if unknown:
            line = lines.get((unknown[0],), 0)
            problems.append(
                f"{where}:{line}: unknown controller keys {unknown} (expected pi, fuzzy-pi)"
            )
        for ctrl in CONTROLLERS:
            if ctrl not in data:
                continue
            val = data[ctrl]
            if val is None:
                val = {}
            provenance: dict[str, Any] = {}
            if isinstance(val, dict) and "gains" in val:
                extra = [str(k) for k in val if k not in _ENTRY_KEYS]
                if extra:
                    line = lines.get((ctrl, extra[0]), 0)
                    problems.append(
                        f"{where}:{line}: unknown key {extra[0]!r} in the {ctrl} entry "
                        f"(expected gains, provenance)"
                    )
                prov = val.get("provenance") or {}
                if not isinstance(prov, dict):
                    line = lines.get((ctrl, "provenance"), 0)
                    problems.append(
                        f"{where}:{line}: provenance must be a mapping (got {type(prov).__name__})"
                    )
                else:
                    provenance = {str(k): v for k, v in prov.items()}
                gains = _check_gains(ctrl, val["gains"], where, lines, (ctrl, "gains"), problems)
            else:
                gains = _check_gains(ctrl, val, where, lines, (ctrl,), problems)
            entries[ctrl] = GainsEntry(ctrl, gains, provenance)
    if problems:
        raise ConfigError("\n".join(problems) if len(problems) > 1 else problems[0])
    return entries


def read_gains_file(path: str | os.PathLike[str]) -> dict[str | None, GainsEntry]:
    """Read and validate a gains file (see :func:`parse_gains`).

    Raises
    ------
    ConfigError
        The file cannot be read, or any problem :func:`parse_gains` reports.
    """
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise ConfigError(f"{path}: cannot read gains file ({exc.strerror})") from exc
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{path}: not a text file ({exc.reason})") from exc
    return parse_gains(text, str(path))


def read_gains(
    path: str | os.PathLike[str] | None, controller: str, required: bool = False
) -> dict[str, float]:
    """The gain overrides for ``controller`` in a gains file ({} when ``path`` is None).

    A flat file applies to any controller. A file keyed by controller that lacks
    ``controller`` is an error when ``required`` (``simulate`` and ``compile``: the user asked
    for that controller with that file), else gives {} and the defaults stay in force
    (``compare``, which runs both controllers and says which ran on defaults).

    Raises
    ------
    ConfigError
        Unknown ``controller``, or any problem of the file (see :func:`parse_gains`); a flat
        file with a key ``controller`` does not take (``kx`` for ``pi``) is an error.
    """
    if controller not in CONTROLLERS:
        raise ConfigError(f"unknown controller {controller!r} (expected pi or fuzzy-pi)")
    if path is None:
        return {}
    entries = read_gains_file(path)
    if None in entries:
        gains = entries[None].gains
        bad = [k for k in gains if k not in GAIN_KEYS[controller]]
        if bad:
            raise ConfigError(
                f"{path}: unknown gain {bad[0]!r} for {controller} "
                f"(expected one of {', '.join(GAIN_KEYS[controller])})"
            )
        # Re-check signs with the controller's own rule (fuzzy-PI needs > 0).
        problems: list[str] = []
        _check_gains(controller, dict(gains), str(path), {}, (), problems)
        if problems:
            raise ConfigError("\n".join(problems))
        return dict(gains)
    entry = entries.get(controller)
    if entry is None and required:
        held = ", ".join(str(k) for k in entries) or "nothing"
        raise ConfigError(
            f"{path}: no gains for {controller} (the file holds: {held}); "
            f"tune {controller} into it or pass a file for {controller}"
        )
    return dict(entry.gains) if entry is not None else {}


def _yaml_value(v: Any) -> Any:
    """Plain YAML-safe values (numpy scalars and tuples become floats and lists)."""
    if isinstance(v, Mapping):
        return {str(k): _yaml_value(x) for k, x in v.items()}
    if isinstance(v, list | tuple):
        return [_yaml_value(x) for x in v]
    if isinstance(v, bool | str | int) or v is None:
        return v
    try:
        return float(v)
    except (TypeError, ValueError):
        return str(v)


def dump_gains(entries: Mapping[str, GainsEntry]) -> str:
    """The YAML text of a gains file holding ``entries`` (keyed by controller name).

    Floats are written with ``repr`` precision so a round trip gives the same numbers.
    """
    import yaml

    doc: dict[str, Any] = {}
    for ctrl in CONTROLLERS:
        if ctrl in entries:
            e = entries[ctrl]
            item: dict[str, Any] = {"gains": _yaml_value(e.gains)}
            if e.provenance:
                item["provenance"] = _yaml_value(e.provenance)
            doc[ctrl] = item
    unknown = sorted(set(entries) - set(CONTROLLERS))
    if unknown:
        raise ConfigError(f"unknown controller keys {unknown} (expected pi, fuzzy-pi)")
    head = "# fuzzkit gains file: read by fuzzkit simulate/compare/compile --gains\n"
    return head + yaml.safe_dump(doc, sort_keys=False, default_flow_style=False)


def write_gains(
    path: str | os.PathLike[str], entry: GainsEntry, merge: bool = True
) -> tuple[Path, list[str]]:
    """Write ``entry`` to a gains file atomically; keep other controllers' entries if ``merge``.

    Returns
    -------
    The path written and the controllers kept from the existing file.

    Raises
    ------
    ConfigError
        ``entry`` has no controller, or (with ``merge``) the existing file is not a valid
        keyed gains file, or the folder does not exist.
    """
    from fuzzkit.fileio import write_atomic

    if entry.controller is None:
        raise ConfigError("a gains entry to write needs a controller (pi or fuzzy-pi)")
    entries: dict[str, GainsEntry] = {}
    kept: list[str] = []
    target = Path(path)
    if merge and target.is_file():
        old = read_gains_file(target)
        for ctrl, e in old.items():
            if ctrl is not None and ctrl != entry.controller:
                entries[ctrl] = e
                kept.append(ctrl)
    entries[entry.controller] = entry
    return write_atomic(target, dump_gains(entries)), kept
