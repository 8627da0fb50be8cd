"""Render a lookup table into source files: ``{relative path: text}``, never written here.

The one object a template sees is a :class:`TableSpec`, built here from the rule base and its
:class:`~fuzzkit.codegen.lookup_table.LookupTable`: every number is already formatted as a
literal of the target language and every name already checked, so templates only lay text out.
Each target lives in
``fuzzkit.codegen/backends/<target>/`` with its templates and a small config (``config.py``, a
:class:`~fuzzkit.codegen.target.Target`): what differs between targets is asked of it, never
branched on here. The helpers every artefact's spec builder shares (checked names, comment-safe
text, wrapped literal lists, the banner's source hash) are here too.
"""

from __future__ import annotations

import functools
import hashlib
import math
import textwrap
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import jinja2
import numpy as np

from fuzzkit.codegen.lookup_table import (
    Q15_RECIP_BITS,
    Q15_T_BITS,
    REFINE_FACTOR,
    ROUNDING_ALLOWANCE,
    LookupTable,
    bound_margin,
    q15_fpi_codes,
)
from fuzzkit.codegen.names import names_note, symbol
from fuzzkit.codegen.target import Target, all_targets, load_target
from fuzzkit.errors import CodegenError
from fuzzkit.fuzzy.model import RuleBase
from fuzzkit.fuzzy.validation import IDENTIFIER, identifier_problem

#: The fuzzy-PI parameters the generated code takes (and a gains file may bake in).
FPI_GAIN_KEYS = ("kp", "ki", "kx", "u_min", "u_max")


@dataclass(frozen=True)
class FpiDefaults:
    """Fuzzy-PI gains baked into the generated code as defaults (from a gains file)."""

    kp: float
    ki: float
    kx: float
    u_min: float
    u_max: float
    #: Where the gains came from (the gains file), for error messages.
    source: str = "gains"


@dataclass(frozen=True)
class AxisSpec:
    """One input axis as the templates need it (literals already formatted)."""

    index: int
    name: str
    low: str
    high: str
    count: int
    stride: int
    uniform: bool
    inv_step: str
    breakpoints: tuple[str, ...]
    # Non-uniform and Q15 axes: bin -> first-guess cell (see LookupTable.index_map)
    map_rows: tuple[str, ...]
    map_type: str
    map_bins: int
    map_scale: str
    inv_widths: tuple[str, ...]
    # Q15 only (empty strings / tuples otherwise)
    scale: str
    q_low: int
    q_high: int
    recip: tuple[str, ...]
    #: " [N]" after the range in comments, or "" (ASCII, comment-safe)
    units: str = ""


@dataclass(frozen=True)
class OutputSpec:
    """One output: its table rows as literal text and its verified bound."""

    index: int
    name: str
    low: str
    high: str
    rows: tuple[str, ...]
    bound: str
    tolerance: str
    scale: str
    #: " [N]" after the range in comments, or "" (ASCII, comment-safe)
    units: str = ""


@dataclass(frozen=True)
class TableSpec:
    """Everything a lookup-table template may use; nothing else reaches the generated text."""

    name: str
    upper: str
    target: str
    number_type: str
    ctype: str
    version: str
    source_file: str
    source_sha256: str
    #: the rule base's own name, which each file's first line quotes (codegen.provenance)
    source_name: str
    #: the header's sentence on a mangled rule-base name (codegen.names), or ""
    names_note: str
    description: tuple[str, ...]
    #: "e [N], de [N], du [mm]" when any variable has units, else ""
    units_line: str
    n_inputs: int
    n_outputs: int
    inputs: tuple[AxisSpec, ...]
    outputs: tuple[OutputSpec, ...]
    shape: str
    n_points: int
    memory_bytes: int
    check_note: tuple[str, ...]
    bound_summary: str
    rounding_note: tuple[str, ...]
    split_bytes: tuple[str, ...]
    has_fpi: bool
    fpi_note: str
    fpi_defaults: dict[str, str] | None
    zero: str
    one: str
    t_bits: int
    t_one: int
    t_half: int
    recip_shift: int


def _check_note(table: LookupTable) -> str:
    """How the bound in a generated header was measured, as ``build_table`` did it."""
    factor = table.check_factor
    grid = (
        f"a grid {factor}x denser than the table along every axis"
        if factor
        else "a grid at least 4x denser than the table along every axis"
    )
    refined = (
        f"; the worst cells resampled {REFINE_FACTOR}x per axis"
        if len(table.breakpoints) == 2 and factor
        else ""
    )
    margin = round(100 * (bound_margin(factor) - 1.0))
    return (
        f"Verified bound: the largest |table - exact engine| over {table.check_points} check "
        f"points ({grid}, so every cell centre and edge midpoint is one{refined}) + {margin} % "
        "for the points between them, rounded up to 3 significant digits:"
    )


def check_name(name: str, what: str) -> str:
    """Return ``name`` if it matches ``[A-Za-z_][A-Za-z0-9_]*`` (keywords included), else raise.

    For the names generated code holds only in strings and comments: a model built in Python
    skips validation, and ``e); system(1`` must never reach a source file.
    """
    if not isinstance(name, str) or not IDENTIFIER.match(name):
        raise CodegenError(
            f"{what} {name!r} is not an identifier (expected [A-Za-z_][A-Za-z0-9_]*)"
        )
    return name


def check_identifier(name: str, what: str) -> str:
    """Return ``name`` if it may appear in the code of every target, else raise CodegenError.

    The model's own rule (``identifier_problem``: C and Python keywords, checked when a file is
    read) comes first, then each target's ``reserved_words``, so a target whose language
    reserves other words refuses them here.
    """
    check_name(name, what)
    why = identifier_problem(name)
    if why is not None:
        raise CodegenError(f"{what} {why}")
    for target in all_targets():
        if name in target.reserved_words:
            raise CodegenError(
                f"{what} {name!r} is reserved in {target.label}; choose another name"
            )
    return name


def check_module_name(name: str, what: str = "rule base") -> str:
    """Return ``name`` if no target's file named after it shadows a standard module, else raise.

    A generated ``math.py`` is imported by its own ``import math`` (and by every other
    ``import math`` beside it), a generated ``stdint.h`` is what ``#include <stdint.h>``
    finds; both break the build far from the cause. Every target is asked (its
    ``module_clash``), so a name is usable whichever target it is compiled to.
    """
    # targets that share a language (C and the FMU) give the same reason once
    clashes = list(dict.fromkeys(why for t in all_targets() if (why := t.module_clash(name))))
    if clashes:
        raise CodegenError(
            f"{what} name {name!r}: " + " and ".join(clashes) + f"; rename the {what}"
        )
    return name


def _comment_safe(text: str) -> str:
    """``text`` made harmless inside a C block comment and a Python docstring."""
    clean = "".join(ch if 32 <= ord(ch) < 127 else "?" for ch in text)
    clean = clean.replace('"""', "'''").replace("\\", "/")
    # "*/" would end the comment, "/*" inside one trips -Wcomment, and "??" can start a
    # trigraph (C99 translates "??/" to a backslash, even in comments: -Wtrigraphs). Repeat
    # until none is left, as a replacement can form the next ("/*/", "???").
    previous = None
    while clean != previous:
        previous = clean
        clean = clean.replace("*/", "* /").replace("/*", "/ *").replace("??", "? ?")
    return clean


#: Unit symbols a C comment cannot hold (comments are ASCII here), spelt out instead of "?".
_UNIT_ASCII = {"°": "deg", "µ": "u", "μ": "u", "²": "^2", "³": "^3", "Ω": "Ohm", "·": "*"}


def units_line(rb: RuleBase) -> str:
    """``e [N], de [N], du [mm]`` for a generated header when any variable has units, else ""."""
    variables = rb.inputs + rb.outputs
    if not any(v.units for v in variables):
        return ""
    return ", ".join(f"{v.name}{units_comment(v.units)}" for v in variables)


def units_comment(units: str | None) -> str:
    """A variable's units as generated comments show them: ``" [N]"``, ``" [degC]"`` or ``""``."""
    if not units:
        return ""
    ascii_units = "".join(_UNIT_ASCII.get(ch, ch) for ch in units)
    return f" [{_comment_safe(ascii_units)}]"


def _check_float32_gains(gains: Mapping[str, float], source: str) -> None:
    """Refuse gains a C ``float`` cannot hold (``NAME_fpi_init`` takes floats)."""
    problems = []
    largest = float(np.finfo(np.float32).max)
    smallest = float(np.finfo(np.float32).smallest_subnormal)
    for key, value in gains.items():
        with np.errstate(over="ignore"):
            single = np.float32(value)
        if not math.isfinite(float(single)):
            problems.append(f"{key}: {value:g} overflows a C float (largest {largest:.7g})")
        elif value != 0.0 and single == 0.0:
            problems.append(
                f"{key}: {value:g} rounds to 0 as a C float "
                f"(smallest non-zero magnitude {smallest:.7g})"
            )
    if problems:
        raise CodegenError(
            f"{source}: fuzzy-PI gains out of float range: "
            + "; ".join(problems)
            + " (rescale the rule base's ranges or use --type double)"
        )


def _rounding_note(number_type: str, target: Target) -> str:
    """How the bound relates to the target's rounding (what verification allows on top)."""
    if number_type == "q15":
        return "Q15: the bound models this integer arithmetic bit for bit (no allowance)."
    allowance = ROUNDING_ALLOWANCE[number_type]
    exponent = round(math.log2(allowance))
    if number_type == "float":
        return (
            "float: the bound is measured on float32 inputs with this file's float32 "
            "breakpoints, constants and arithmetic, operation for operation; a compiler that "
            f"fuses multiply-adds (FMA) may differ by up to 2^{exponent} of an output's full "
            "scale (largest |range end|), which verification allows on top."
        )
    runtime = target.runtime[number_type]
    return (
        f"double: the bound is measured in float64; {runtime} may differ by up to "
        f"2^{exponent} of an output's full scale (largest |range end|), allowed on top."
    )


def _wrap(items: Sequence[str], per_line: int, width: int = 94) -> tuple[str, ...]:
    """Join ``items`` with ", " into lines of at most ``per_line`` items and ``width`` chars."""
    lines: list[str] = []
    current: list[str] = []
    for item in items:
        candidate = ", ".join([*current, item])
        if current and (len(current) >= per_line or len(candidate) > width):
            lines.append(", ".join(current))
            current = []
        current.append(item)
    if current:
        lines.append(", ".join(current))
    return tuple(lines)


def source_sha256(rb: RuleBase) -> tuple[str, str]:
    """The rule base's file name and sha256 as the banner states them."""
    if rb.source is not None:
        return Path(rb.source.path).name, rb.source.sha256
    # A model built in Python has no file: hash its canonical repr so the banner still
    # identifies what the code came from.
    return "<model>", hashlib.sha256(repr(rb).encode("utf-8")).hexdigest()


def build_spec(
    rb: RuleBase,
    table: LookupTable,
    target: str,
    *,
    fpi_defaults: FpiDefaults | None = None,
) -> TableSpec:
    """Collect, check and format everything the ``target`` templates need.

    Raises
    ------
    CodegenError
        Unknown target, a name that cannot be an identifier, or a table of another type
        than the target computes in (the Python target needs ``double``).
    """
    from fuzzkit import __version__

    tg = load_target(target)
    tg.check_number_type(table.number_type, f"a {table.number_type} table")
    # only the rule base's name is an identifier in the code (keywords mangled); variable
    # names are strings and comments there, so they need only be identifiers, keywords too
    name = check_module_name(check_identifier(symbol(rb.name), "rule base name"))
    for var in rb.inputs + rb.outputs:
        check_name(var.name, f"variable name ({rb.name})")
    nt = table.number_type

    def lit(v: float) -> str:
        return tg.literal(v, nt)

    per_line = tg.values_per_line["table"]
    shape = table.shape
    strides = [math.prod(shape[a + 1 :]) for a in range(len(shape))]
    axes = []
    for a, var in enumerate(rb.inputs):
        bp = table.breakpoints[a]
        q = table.q15
        uniform = q is None and table.is_uniform(a)
        map_rows: tuple[str, ...] = ()
        map_bins = 0
        map_scale = ""
        if not uniform:
            cells, scale = table.index_map(a)
            map_rows = _wrap([str(int(c)) for c in cells], 16)
            map_bins = int(cells.size)
            map_scale = str(int(scale)) if q is not None else lit(scale)
        axes.append(
            AxisSpec(
                index=a,
                name=var.name,
                low=lit(float(bp[0])),
                high=lit(float(bp[-1])),
                count=len(bp),
                stride=strides[a],
                uniform=uniform,
                inv_step=lit((len(bp) - 1) / (float(bp[-1]) - float(bp[0]))),
                breakpoints=_wrap(
                    [str(int(v)) for v in q.q_breakpoints[a]]
                    if q is not None
                    else [lit(float(v)) for v in bp],
                    per_line,
                ),
                map_rows=map_rows,
                map_type="unsigned char" if len(bp) <= 257 else "unsigned short",
                map_bins=map_bins,
                map_scale=map_scale,
                inv_widths=()
                if uniform or q is not None
                else _wrap([lit(1.0 / float(w)) for w in np.diff(bp)], 8),
                scale=tg.literal(q.in_scale[a], "double") if q is not None else "",
                q_low=q.q_low[a] if q is not None else 0,
                q_high=q.q_high[a] if q is not None else 0,
                recip=_wrap([str(int(v)) for v in q.recip[a]], 8) if q is not None else (),
                units=units_comment(var.units),
            )
        )
    outputs = []
    for k, var in enumerate(rb.outputs):
        flat = np.asarray(table.stored[k]).ravel()
        items = [str(int(v)) for v in flat] if nt == "q15" else [lit(float(v)) for v in flat]
        outputs.append(
            OutputSpec(
                index=k,
                name=var.name,
                low=format(var.low, ".6g"),
                high=format(var.high, ".6g"),
                rows=_wrap(items, per_line),
                bound=format(table.bound[k], ".3g"),
                tolerance=format(table.tolerance[k], ".3g") if table.tolerance else "",
                scale=tg.literal(table.q15.out_scale[k], "double") if table.q15 else "",
                units=units_comment(var.units),
            )
        )
    split_bytes: tuple[str, ...] = ()
    if table.splits is not None:
        bits = np.packbits(table.splits.ravel(), bitorder="little")
        split_bytes = _wrap([f"0x{int(b):02x}" for b in bits], 12)
    has_fpi = len(rb.inputs) == 2
    if len(rb.inputs) != 2:
        note = (
            "no fuzzy-PI API: it needs exactly 2 inputs (e, de), this rule base has "
            f"{len(rb.inputs)}"
        )
    else:
        note = ""
    defaults = None
    if fpi_defaults is not None and has_fpi:
        gains = {k: float(getattr(fpi_defaults, k)) for k in FPI_GAIN_KEYS}
        if nt in ("float", "q15"):
            _check_float32_gains(gains, fpi_defaults.source)
        defaults = {k: lit(v) for k, v in gains.items()}
        if table.q15 is not None:  # Q15 bakes the codes: no floating point in the C
            codes = q15_fpi_codes(table.q15, *(gains[k] for k in FPI_GAIN_KEYS))
            defaults = {k: str(c) for k, c in zip(FPI_GAIN_KEYS, codes, strict=True)}
    file_name, sha = source_sha256(rb)
    desc = tuple(textwrap.wrap(_comment_safe(" ".join(rb.description.split())), 88)[:8])
    bound_summary = table.bound_summary()  # as fuzzkit compile prints it
    return TableSpec(
        name=name,
        upper=name.upper(),
        target=target,
        number_type=nt,
        ctype=tg.type_names[nt],
        version=__version__,
        source_file=_comment_safe(file_name),
        source_sha256=sha,
        source_name=rb.name,
        names_note=names_note(rb.name),
        description=desc,
        units_line=units_line(rb),
        n_inputs=len(rb.inputs),
        n_outputs=len(rb.outputs),
        inputs=tuple(axes),
        outputs=tuple(outputs),
        shape="x".join(str(n) for n in shape),
        n_points=table.n_points,
        memory_bytes=table.memory_bytes,
        check_note=tuple(textwrap.wrap(_check_note(table), 92)),
        bound_summary=bound_summary,
        rounding_note=tuple(textwrap.wrap(_rounding_note(nt, tg), 88)),
        split_bytes=split_bytes,
        has_fpi=has_fpi,
        fpi_note=note.replace("NAME", name),
        fpi_defaults=defaults,
        zero=lit(0.0),
        one=lit(1.0),
        t_bits=Q15_T_BITS,
        t_one=1 << Q15_T_BITS,
        t_half=1 << (Q15_T_BITS - 1),
        recip_shift=Q15_RECIP_BITS - Q15_T_BITS,
    )


@functools.cache
def _environment(target: str) -> jinja2.Environment:
    """The one Jinja setup every target's templates are rendered with.

    One environment per target and process: Jinja keeps the compiled templates in it (and
    recompiles a template file that changed on disk), so emitting again, once per tuning
    candidate, does not parse and compile every template again (that took 80 % of a `tune`).
    """
    return jinja2.Environment(
        loader=jinja2.FileSystemLoader([str(f) for f in load_target(target).template_folders()]),
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
        autoescape=False,
    )


def render_files(target: str, name: str, spec: Any, artefact: str = "table") -> dict[str, str]:
    """Render the ``artefact`` templates of ``target`` with its one spec object ``spec``.

    ``artefact`` is a key of the target's ``files`` (``table``, ``exact``, ``controller``).
    """
    outputs = load_target(target).files.get(artefact)
    if outputs is None:
        raise CodegenError(f"the {target} target has no {artefact} templates")
    env = _environment(target)
    files: dict[str, str] = {}
    for pattern, template in outputs.items():
        path = pattern.format(name=name)
        try:
            files[path] = env.get_template(template).render(spec=spec)
        except jinja2.TemplateError as exc:  # a template bug, not user input
            raise CodegenError(f"template {target}/{template}: {exc}") from exc
    return files


def render(spec: TableSpec) -> dict[str, str]:
    """Render every file of ``spec.target``: ``{relative path: text}``."""
    return render_files(spec.target, spec.name, spec)


def emit(
    rb: RuleBase,
    table: LookupTable,
    target: str,
    *,
    fpi_defaults: FpiDefaults | None = None,
) -> dict[str, str]:
    """Generate the ``target`` sources for ``rb`` from ``table``: ``{relative path: text}``."""
    return render(build_spec(rb, table, target, fpi_defaults=fpi_defaults))
