"""What ran the controller in each run of the report (issue 37, item 2): the report's
``runs.json`` (one record per run, the run's own ``controller_impl``) and its markdown section,
both read from the runs' results, never assumed."""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

from fuzzkit.loop.result import implementations

#: the keys of a run's summary a record keeps (the rest is in the report's tables)
RECORD_KEYS = (
    "experiment",
    "controller",
    "plant",
    "stiffness",
    "latency_periods",
    "tripped",
    "loop",
    "controller_impl",
)


def record(part: str, data: Mapping[str, Any], **extra: Any) -> dict[str, Any]:
    """One run's record: which part of the report ran it, ``extra`` (its gains label, its
    condition, its spec ...) and :data:`RECORD_KEYS` of its summary (``fuzzkit simulate
    --json``'s, or any mapping with a ``controller_impl``)."""
    return {"part": part, **extra, **{k: data[k] for k in RECORD_KEYS if k in data}}


def runs_json(records: Sequence[Mapping[str, Any]]) -> str:
    """The text of ``runs.json``."""
    return json.dumps({"runs": list(records)}, indent=1) + "\n"


def section(records: Iterable[Mapping[str, Any]]) -> list[str]:
    """The markdown lines of the section: per part of the report, its runs and what ran them."""
    parts: dict[str, list[str]] = {}
    counts: dict[str, int] = {}
    for r in records:
        part = str(r["part"])
        parts.setdefault(part, []).append(str(r["controller_impl"]))
        counts[part] = counts.get(part, 0) + int(r.get("runs", 1))  # a latency map: its runs
    md = [
        "",
        "## What ran the controller",
        "",
        "As each run reports it (its `controller_impl`; every run is listed in `runs.json`).",
        "",
        "| part | runs | controller implementation |",
        "|---|---:|---|",
    ]
    for part, labels in parts.items():
        md.append(f"| {part} | {counts[part]} | {implementations(labels)} |")
    md.append("")
    return md
