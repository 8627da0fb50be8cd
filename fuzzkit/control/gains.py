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
``rate_limit > 0`` (m per step). Every problem is reported at once as ``file:line:col: what
(expected X, got Y)`` in one :class:`~fuzzkit.errors.ConfigFileError` (a ``ConfigError``).
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from fuzzkit.control.names import GAIN_KEYS, GAIN_LIMIT_KEYS
from fuzzkit.control.names import KINDS as CONTROLLERS
from fuzzkit.errors import ConfigError, ConfigFileError, Location, Problem
from fuzzkit.located_yaml import (
    DocumentKind,
    compose_document,
    locations,
    raise_problems,
    read_document,
    to_python,
)

#: The keys a gains file accepts per controller: its scaling factors, then the limits.
FILE_KEYS: dict[str, tuple[str, ...]] = {
    kind: (*GAIN_KEYS[kind], *GAIN_LIMIT_KEYS) for kind in GAIN_KEYS
}

#: Every gain key of any controller (a flat file may hold any of them).
_ALL_KEYS = tuple(dict.fromkeys(k for keys in FILE_KEYS.values() for k in keys))

#: Keys of a structured entry (``{gains: ..., provenance: ...}``).
_ENTRY_KEYS = ("gains", "provenance")


@dataclass(frozen=True, slots=True)
class GainsEntry:
    """The gains of one controller and where they came from (free-form, for humans)."""

    controller: str | None  # None: a flat file that applies to any controller
    gains: dict[str, float]
    provenance: dict[str, Any] = field(default_factory=dict)


GAINS_DOCUMENT = DocumentKind(
    "gains file",
    "gains files",
    "expected a mapping of gains (kp: ..., ki: ...) or of controllers (pi: ..., fuzzy-pi: ...)",
    ConfigFileError,
)

_Where = dict[tuple[str | int, ...], Location]


def _check_gains(
    controller: str | None,
    data: Any,
    where: str,
    lines: _Where,
    path: tuple[str, ...],
    problems: list[Problem],
) -> dict[str, float]:
    """Validate one gains mapping; append located problems; return the valid gains."""

    def at(*keys: str) -> Location:
        return lines.get((*path, *keys)) or lines.get(path) or Location(where)

    if not isinstance(data, dict):
        problems.append(Problem(at(), f"gains must be a mapping (got {type(data).__name__})"))
        return {}
    allowed = FILE_KEYS[controller] if controller else _ALL_KEYS
    out: dict[str, float] = {}
    for k, val in data.items():
        if k not in allowed:
            problems.append(
                Problem(
                    at(k),
                    f"unknown gain {k!r}"
                    + (f" for {controller}" if controller else "")
                    + f" (expected one of {', '.join(allowed)})",
                )
            )
        elif isinstance(val, bool) or not isinstance(val, int | float) or not math.isfinite(val):
            problems.append(Problem(at(k), f"gain {k} must be a finite number (got {val!r})"))
        else:
            out[k] = float(val)
    # Sign and order checks the controllers would make, but located in the file.
    strict = controller == "fuzzy-pi"
    for k in GAIN_KEYS["fuzzy-pi"]:
        if k in out and (out[k] <= 0.0 if strict else out[k] < 0.0):
            want = "> 0" if strict else ">= 0"
            problems.append(Problem(at(k), f"gain {k} must be {want} (got {out[k]!r})"))
    if "u_min" in out and out["u_min"] > 0.0:
        problems.append(Problem(at("u_min"), f"u_min must be <= 0 (got {out['u_min']!r})"))
    if "u_max" in out and out["u_max"] < 0.0:
        problems.append(Problem(at("u_max"), f"u_max must be >= 0 (got {out['u_max']!r})"))
    if "rate_limit" in out and out["rate_limit"] <= 0.0:
        problems.append(
            Problem(at("rate_limit"), f"rate_limit must be > 0 (got {out['rate_limit']!r})")
        )
    return out


def parse_gains(text: str, where: str = "<gains>") -> dict[str | None, GainsEntry]:
    """Parse a gains file's text into entries keyed by controller (None: a flat file).

    The text is read by :mod:`fuzzkit.located_yaml` (size and alias limits, duplicate and
    boolean keys refused, ``1e-4`` read as a number).

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
        (a :class:`~fuzzkit.errors.ConfigFileError`) Not YAML, not a mapping, unknown
        controllers or keys, non-finite or out-of-range gains: every problem, each as
        ``file:line:col: ...``.
    """
    root = compose_document(text, where, GAINS_DOCUMENT)
    data = to_python(root, where, GAINS_DOCUMENT)
    lines = locations(root, where)
    if not isinstance(data, dict):
        raise ConfigFileError(
            [Problem(lines[()], f"expected a mapping of gains, got {type(data).__name__}")]
        )
    problems: list[Problem] = []
    entries: dict[str | None, GainsEntry] = {}
    if not any(k in CONTROLLERS for k in data):
        gains = _check_gains(None, data, where, lines, (), problems)
        entries[None] = GainsEntry(None, gains)
    else:
        unknown = [k for k in data if k not in CONTROLLERS]
        if unknown:
            problems.append(
                Problem(
                    lines[(unknown[0],)],
                    f"unknown controller keys {unknown} (expected pi, fuzzy-pi)",
                )
            )
        for ctrl in CONTROLLERS:
            if ctrl not in data:
                continue
            val = data[ctrl]
            if val is None:
                val = {}
            provenance: dict[str, Any] = {}
            if isinstance(val, dict) and "gains" in val:
                extra = [k for k in val if k not in _ENTRY_KEYS]
                if extra:
                    problems.append(
                        Problem(
                            lines[(ctrl, extra[0])],
                            f"unknown key {extra[0]!r} in the {ctrl} entry "
                            "(expected gains, provenance)",
                        )
                    )
                prov = val.get("provenance") or {}
                if not isinstance(prov, dict):
                    problems.append(
                        Problem(
                            lines[(ctrl, "provenance")],
                            f"provenance must be a mapping (got {type(prov).__name__})",
                        )
                    )
                else:
                    provenance = dict(prov)
                gains = _check_gains(ctrl, val["gains"], where, lines, (ctrl, "gains"), problems)
            else:
                gains = _check_gains(ctrl, val, where, lines, (ctrl,), problems)
            entries[ctrl] = GainsEntry(ctrl, gains, provenance)
    if problems:
        raise_problems(problems, GAINS_DOCUMENT)
    return entries


def read_gains_file(path: str | os.PathLike[str]) -> dict[str | None, GainsEntry]:
    """Read and validate a gains file (see :func:`parse_gains`).

    Raises
    ------
    ConfigError
        The file cannot be read, or any problem :func:`parse_gains` reports.
    """
    return parse_gains(read_document(Path(path), GAINS_DOCUMENT), str(path))


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
        bad = [k for k in gains if k not in FILE_KEYS[controller]]
        if bad:
            raise ConfigError(
                f"{path}: unknown gain {bad[0]!r} for {controller} "
                f"(expected one of {', '.join(FILE_KEYS[controller])})"
            )
        # Re-check signs with the controller's own rule (fuzzy-PI needs > 0).
        problems: list[Problem] = []
        _check_gains(controller, dict(gains), str(path), {}, (), problems)
        if problems:
            raise_problems(problems, GAINS_DOCUMENT)
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
