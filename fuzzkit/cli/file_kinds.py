"""Every kind of file fuzzkit reads, recognised by its content: what ``fuzzkit validate`` checks,
and what ``info``, ``eval``, ``plot`` and ``surface`` refuse when given another kind than a
rule base (:func:`require_rulebase`).

A kind is one :class:`FileKind` entry in :data:`KINDS`: how to recognise it (the top-level
YAML keys that only it has, or the first word of a foreign rule-base format) and how to check
it (its own strict reader, which raises a :class:`~fuzzkit.errors.ProblemsError` with every
problem at ``file:line:col``). Adding a kind is adding one entry.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from fuzzkit.errors import ConfigError, FuzzkitError, Location, Problem, ProblemsError
from fuzzkit.formats.registry import (
    FORMATS,
    READERS,
    RULEBASE_SUFFIXES,
    available,
    load_with_warnings,
)

#: How much of a file is read to recognise it (the kind's own reader reads the whole file).
SNIFF_BYTES = 65536


@dataclass(frozen=True, slots=True)
class Checked:
    """A file that passed its kind's reader: a one-line summary and any warnings."""

    summary: str
    warnings: tuple[Problem, ...] = ()


@dataclass(frozen=True, slots=True)
class FileKind:
    """One kind of file: its name, how it is recognised, how it is checked.

    ``yaml_keys``: top-level keys of a YAML document that mark this kind (the kind whose keys
    a document has most of wins). ``first_words``: the first word of a foreign text format
    (``[System]`` for a .fis file) and the file suffix its reader goes by. ``shipped``: the
    names of shipped files of this kind (``fuzzkit validate E1``). ``check(path_or_name,
    suffix)`` reads it with the kind's strict reader (``suffix``: the format recognised, or
    "" for YAML) and returns :class:`Checked`, or raises a ProblemsError.
    """

    name: str
    yaml_keys: frozenset[str]
    check: Callable[[str, str], Checked]
    shipped: Callable[[], list[str]]
    first_words: tuple[tuple[str, str], ...] = ()


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}{'' if n == 1 else 's'}"


def _check_rulebase(spec: str, suffix: str) -> Checked:
    if suffix and Path(spec).suffix.lower() != suffix:
        rb, warnings = READERS[suffix](Path(spec))  # e.g. a .txt holding a .fis rule base
    else:
        rb, warnings = load_with_warnings(spec)
    return Checked(
        f"rule base {rb.name}: {_count(len(rb.inputs), 'input')}, "
        f"{_count(len(rb.outputs), 'output')}, {_count(len(rb.rules), 'rule')}",
        tuple(warnings),
    )


def _check_scenario(spec: str, suffix: str) -> Checked:
    from fuzzkit.studies.experiments import EXPERIMENTS, experiment
    from fuzzkit.studies.scenario_file import load_scenario

    exp = experiment(spec) if spec.upper() in EXPERIMENTS else load_scenario(spec)
    axes = ", ".join(
        f"{axis} {sp:g} N"
        for axis, sel, sp in zip("xyz", exp.selection, exp.setpoints, strict=True)
        if sel
    )
    warnings: tuple[Problem, ...] = ()
    cs = exp.controller_spec
    if cs is not None:
        from fuzzkit.control.impact import impact_warning, path_approach_speed

        speed = path_approach_speed(exp.scenario.path, cs.selection)
        msg = impact_warning(cs, speed, sum(exp.latency_periods), "the path")
        if msg is not None:
            warnings = (Problem(Location(spec), msg, "warning"),)
    return Checked(
        f"scenario {exp.name}: {exp.scenario.duration_s:g} s, force control {axes}, "
        f"safety limit {exp.force_limit_n:g} N",
        warnings,
    )


def _shipped_scenarios() -> list[str]:
    from fuzzkit.studies.experiments import EXPERIMENTS

    return list(EXPERIMENTS)


def _check_spec(spec: str, suffix: str) -> Checked:
    from fuzzkit.control.spec_reader import load_spec

    ctl = load_spec(spec)
    axes = ", ".join(f"{a.axis} {a.setpoint_n:g} N" for a in ctl.axes)
    rb = f" on {ctl.rulebase.name}" if ctl.rulebase is not None else ""
    from fuzzkit.control.impact import impact_speed

    v = impact_speed(ctl)
    impact = ""
    if v is not None:
        est = ctl.adaptation.estimator
        impact = (
            f"; impact speed {v * 1e3:.3g} mm/s (k_max {est.k_max_n_mm:g} N/mm, latency "
            f"{est.delay_periods - 1} periods: a faster approach passes the safety limit on "
            "impact alone)"
        )
    return Checked(f"controller spec {ctl.name}: {ctl.kind}{rb}; {axes}{impact}")


def _check_gains(spec: str, suffix: str) -> Checked:
    from fuzzkit.control.gains import read_gains_file

    entries = read_gains_file(spec)
    parts = [
        (entry.controller or "any controller")
        + " ("
        + ", ".join(f"{k}={v:g}" for k, v in entry.gains.items())
        + ")"
        for entry in entries.values()
    ]
    return Checked("gains file: " + "; ".join(parts))


def _no_shipped() -> list[str]:
    return []


#: Every kind ``fuzzkit validate`` knows, in the order named in messages.
KINDS: tuple[FileKind, ...] = (
    FileKind(
        "rule base",
        frozenset({"inputs", "outputs", "rules", "operators", "defuzzifier"}),
        _check_rulebase,
        available,
        first_words=tuple((f.first_word, f.suffix) for f in FORMATS.values()),
    ),
    FileKind(
        "scenario",
        frozenset({"force_control", "objects", "path", "safety_limit_n", "duration_s"}),
        _check_scenario,
        _shipped_scenarios,
    ),
    FileKind(
        "controller spec",
        frozenset({"controller", "axes", "limits", "safety", "adaptation"}),
        _check_spec,
        _no_shipped,
    ),
    FileKind(
        "gains file",
        frozenset({"pi", "fuzzy-pi", "kp", "ki", "kx", "u_min", "u_max", "rate_limit"}),
        _check_gains,
        _no_shipped,
    ),
)

#: What each kind is for, said when a command is given a kind it does not read.
READ_BY = {
    "rule base": "fuzzkit info, eval, plot, surface, compile",
    "scenario": "fuzzkit simulate, compare, sweep, tune, stability",
    "controller spec": "fuzzkit simulate --spec, compile, replay, tune --spec",
    "gains file": "fuzzkit simulate --gains, compare --gains, stability --gains",
}

_TOP_KEY = re.compile(r"^([A-Za-z_][A-Za-z0-9_-]*)\s*:", re.M)
_BLOCK_COMMENT = re.compile(r"\(\*.*?\*\)|/\*.*?\*/", re.S)
_LINE_COMMENT = re.compile(r"^\s*(#|%|//).*$", re.M)


def recognise(spec: str) -> tuple[FileKind, str]:
    """The kind of file ``spec`` is (a path, or a shipped name) and the foreign format's suffix
    ("" for YAML).

    Raises
    ------
    ProblemsError
        The file cannot be read, or its content is no kind fuzzkit reads (the kinds and what
        marks each are listed).
    """
    path = Path(spec)
    if not path.exists():
        for kind in KINDS:
            if spec in kind.shipped() or spec.upper() in kind.shipped():
                return kind, ""
        # not a file and no shipped name: the rule-base reader names what was meant
        return KINDS[0], ""
    if path.is_dir():
        raise ProblemsError([Problem(Location(spec), "is a folder (expected a file)")])
    try:
        with path.open("rb") as fh:
            head = fh.read(SNIFF_BYTES).decode("utf-8", errors="replace")
    except OSError as exc:
        raise ProblemsError(
            [Problem(Location(spec), f"cannot read: {exc.strerror or exc}")]
        ) from None
    text = _LINE_COMMENT.sub("", _BLOCK_COMMENT.sub("", head)).lstrip()
    for kind in KINDS:
        for word, suffix in kind.first_words:
            if text.startswith(word):
                return kind, suffix
    keys = set(_TOP_KEY.findall(head))
    if not keys and path.suffix.lower() in RULEBASE_SUFFIXES:
        return KINDS[0], ""  # no readable top level: the rule-base reader locates what is wrong
    scores = sorted(((len(kind.yaml_keys & keys), i) for i, kind in enumerate(KINDS)), reverse=True)
    best, index = scores[0]
    if best == 0 or (len(scores) > 1 and scores[1][0] == best):
        raise ProblemsError([Problem(Location(spec, 1, 1), _unknown_kind_message(keys))])
    return KINDS[index], ""


def _unknown_kind_message(keys: set[str]) -> str:
    marks = "; ".join(
        f"a {kind.name} ("
        + ", ".join([*sorted(kind.yaml_keys)[:3], *(f"{word} ..." for word, _ in kind.first_words)])
        + ")"
        for kind in KINDS
    )
    found = ", ".join(sorted(keys)) if keys else "no top-level keys"
    return f"not a file fuzzkit reads (found {found}); expected {marks}"


def check_file(spec: str) -> Checked:
    """Recognise ``spec`` and check it with its kind's reader.

    Raises
    ------
    ProblemsError
        Every problem, located, or why the file is no kind fuzzkit reads.
    """
    kind, suffix = recognise(spec)
    return kind.check(spec, suffix)


def require_rulebase(spec: str, command: str) -> None:
    """Refuse ``spec`` before the rule-base reader sees it when its content is another kind
    of file: the error says what it is, what ``fuzzkit COMMAND`` wants, and which commands
    read it (a rule base, or a file of no known kind, passes: the rule-base reader locates
    what is wrong with it).

    Raises
    ------
    ConfigError
        ``spec`` is a scenario, a controller spec or a gains file.
    """
    try:
        kind, _ = recognise(spec)
    except ProblemsError:
        return
    if kind is KINDS[0]:
        return
    hint = ""
    if kind.name == "controller spec":
        try:
            from fuzzkit.control.spec_reader import load_spec

            source = load_spec(spec).rulebase_source
        except FuzzkitError:
            source = None
        if source:
            hint = f"; its rule base is {source}: fuzzkit {command} {source}"
    raise ConfigError(
        f"{spec}: is a {kind.name}, not a rule base (fuzzkit {command} reads rule bases: "
        f"YAML, .fis, .fcl, .fll, or a shipped name); a {kind.name} is read by "
        f"{READ_BY[kind.name]}, and checked by fuzzkit validate{hint}"
    )


def is_kind(spec: str, name: str) -> bool:
    """True when ``spec`` is recognised as the kind called ``name`` (``"controller spec"`` ...);
    False also when it cannot be recognised (the reader the caller uses reports why)."""
    try:
        return recognise(spec)[0].name == name
    except ProblemsError:
        return False
