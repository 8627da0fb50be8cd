"""``fuzzkit validate | info | eval | surface | schema``: working with rule bases.

Every RULEBASE argument is a path to a YAML file or the name of a shipped rule base.
``validate`` and ``schema`` also take controller specs (``docs/controller.md``).
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import math
import sys
import textwrap
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any, TextIO

from fuzzkit.cli import RULEBASE_SPEC_HELP, numbers
from fuzzkit.errors import EvaluationError, FuzzkitError, Location, Problem, ProblemsError
from fuzzkit.fileio import check_output_path
from fuzzkit.fuzzy.describe import num as _num
from fuzzkit.fuzzy.describe import range_text, rule_grid, rule_sentence, shown_output
from fuzzkit.fuzzy.model import SHAPE_PARAMS, RuleBase, Variable
from fuzzkit.fuzzy.type2_model import Footprint, footprint_of
from fuzzkit.viz.figures import figure_format

EXIT_OK = 0
EXIT_BAD_INPUT = 2


def register(sub: Any) -> None:
    """Add the rule-base subcommands to the ``fuzzkit`` parser."""
    p = sub.add_parser(
        "validate",
        help="check any file fuzzkit reads (rule bases, scenarios, controller specs, gains "
        "files); list every problem",
        description="Check files fuzzkit reads, each recognised by its content: rule bases "
        "(YAML, .fis, .fcl, .fll), scenario files, controller specs (docs/controller.md) and "
        "gains files (fuzzkit tune's); "
        "paths, shipped rule-base names or E1, E2, E3. Exit 0 when all are valid, 2 listing "
        "every problem (file:line:col) otherwise. "
        "Warnings (input ranges no term covers, in rule bases with coverage: allow_gaps) are "
        "printed and do not fail unless --strict is given.",
        epilog="examples:\n"
        "  fuzzkit validate rulebases/*.yaml\n"
        "  fuzzkit validate --strict my_controller.yaml macvicar_whelan\n"
        "  fuzzkit validate my_task.yaml docs/examples/heater.fis E1\n"
        "  fuzzkit validate docs/examples/controller.yaml",
    )
    p.add_argument(
        "files",
        nargs="+",
        metavar="FILE",
        help="a rule-base, scenario, controller-spec or gains file, or a shipped name (any number)",
    )
    p.add_argument("--strict", action="store_true", help="treat warnings (coverage gaps) as errors")
    p.set_defaults(handler=cmd_validate)

    p = sub.add_parser(
        "info",
        help="describe a rule base: variables, terms, rules (or summarise any file fuzzkit reads)",
        description="Print a rule base's variables with ranges, their terms with "
        "shapes and parameters, and its rules (as a grid for tables). Any other file fuzzkit "
        "reads (a scenario, a controller spec, a gains file; told by content) is summarised "
        "in one line, a controller spec's rule base described after it.",
        epilog="examples:\n  fuzzkit info macvicar_whelan\n  fuzzkit info my_controller.yaml\n"
        "  fuzzkit info docs/examples/controller.yaml",
    )
    p.add_argument(
        "rulebase",
        metavar="FILE",
        help=RULEBASE_SPEC_HELP + "; or a scenario, controller-spec or gains file",
    )
    p.set_defaults(handler=cmd_info)

    p = sub.add_parser(
        "eval",
        help="evaluate a rule base at a point or at CSV rows",
        description="Evaluate a rule base with the exact engine, at one point "
        "(--input NAME=VALUE for every input) or at every row of a CSV "
        "file (--points, header = input names; the rows are echoed "
        "with the outputs appended). NaN inputs give NaN outputs.",
        epilog="examples:\n"
        "  fuzzkit eval macvicar_whelan -i e=0.25 -i de=-0.1\n"
        "  fuzzkit eval macvicar_whelan --points points.csv > out.csv\n"
        "  fuzzkit eval macvicar_whelan -i e=0.25 -i de=-0.1 --explain --png why.png",
    )
    p.add_argument("rulebase", metavar="RULEBASE", help=RULEBASE_SPEC_HELP)
    group = p.add_mutually_exclusive_group(required=True)
    group.add_argument(
        "--input",
        "-i",
        action="append",
        metavar="NAME=VALUE",
        dest="inputs",
        help="an input value (repeat for every input)",
    )
    group.add_argument(
        "--points",
        metavar="FILE.csv",
        help="CSV file with a header of input names ('-' reads stdin)",
    )
    p.add_argument("--json", action="store_true", help="print the point's outputs as JSON")
    p.add_argument(
        "--explain",
        action="store_true",
        help="also say why (one --input point): the fuzzified inputs, every rule that fires "
        "with its strength, and each output's aggregated set (with --json: as data)",
    )
    p.add_argument(
        "--png",
        metavar="OUT.png",
        help="with --explain: draw the rule view (as MATLAB's rule viewer): a row per rule "
        "that fires with its input terms, the input value, the firing strength and the cut "
        "consequent, then each output's aggregated set and defuzzified value",
    )
    p.add_argument(
        "--rules",
        type=numbers.RULES_DRAWN,
        default=12,
        metavar="N",
        help="with --png: draw the N strongest rules that fire, 1 to 64 (default: 12)",
    )
    p.set_defaults(handler=cmd_eval)

    p = sub.add_parser(
        "surface",
        help="write the control surface of a rule base over two of its inputs",
        description="Compute the control surface output = F(input1, input2) with "
        "the exact engine and write it as a Rerun recording (3-D mesh "
        "plus the label-peak grid; 2-input rule bases) and/or a PNG. With more than two "
        "inputs, choose two with --inputs and hold the others with --fix (like MATLAB's "
        "gensurf).",
        epilog="examples:\n"
        "  fuzzkit surface macvicar_whelan --png surface.png\n"
        "  fuzzkit surface gaussian5 --rrd surface.rrd --resolution 201\n"
        "  fuzzkit surface three_input --inputs e,de --fix r=0.5 --png slice.png\n"
        "  rerun surface.rrd     (open the recording in the Rerun viewer)",
    )
    p.add_argument("rulebase", metavar="RULEBASE", help=RULEBASE_SPEC_HELP)
    p.add_argument("--rrd", metavar="OUT.rrd", help="Rerun recording to write")
    p.add_argument("--png", metavar="OUT.png", help="PNG image to write")
    p.add_argument(
        "--resolution",
        type=numbers.SURFACE_RESOLUTION,
        default=101,
        metavar="N",
        help="grid points per input (default 101)",
    )
    p.add_argument("--output", metavar="NAME", help="which output (default: the first)")
    p.add_argument(
        "--inputs",
        metavar="X,Y",
        help="the two inputs to span, e.g. --inputs e,r (default: the first two)",
    )
    p.add_argument(
        "--fix",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="hold another input at VALUE (repeat per input; default: the middle of its range)",
    )
    p.set_defaults(handler=cmd_surface)

    p = sub.add_parser(
        "schema",
        help="print the JSON Schema of the rule-base (or scenario, or controller-spec) format",
        description="Print a JSON Schema (draft 2020-12) of the rule-base YAML "
        "format, e.g. for the YAML language server.",
        epilog="examples:\n  fuzzkit schema > fuzzkit-rulebase.schema.json\n"
        "  fuzzkit schema --controller > fuzzkit-controller.schema.json",
    )
    which = p.add_mutually_exclusive_group()
    which.add_argument(
        "--scenario",
        action="store_true",
        help="the schema of scenario files (fuzzkit simulate TASK.yaml) instead",
    )
    which.add_argument(
        "--controller",
        action="store_true",
        help="the schema of controller specs (docs/controller.md) instead",
    )
    p.set_defaults(handler=cmd_schema)


def _load(spec: str, command: str) -> RuleBase:
    """The rule base ``spec``; another kind of file (a scenario, a controller spec, a gains
    file) is refused with what it is and what reads it."""
    from fuzzkit.cli.file_kinds import require_rulebase
    from fuzzkit.formats.registry import load

    require_rulebase(spec, command)
    return load(spec)


# ---------------------------------------------------------------------------- validate


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}{'' if n == 1 else 's'}"


def cmd_validate(args: argparse.Namespace) -> int:
    """Recognise and check every file, print ``FILE: ok (...)`` or every problem; exit 2 if any
    is invalid (:mod:`fuzzkit.cli.file_kinds` says which kinds and how they are told apart)."""
    from fuzzkit.cli.file_kinds import check_file

    failed = 0
    for spec in args.files:
        try:
            checked = check_file(spec)
        except ProblemsError as exc:
            failed += 1
            for problem in exc.problems:
                print(f"{problem}", file=sys.stderr)
            continue
        except FuzzkitError as exc:
            failed += 1
            print(f"{spec}: {exc}", file=sys.stderr)
            continue
        warnings = checked.warnings
        for warning in warnings:
            if args.strict:
                print(
                    f"{warning.location}: {warning.message} (an error under --strict)",
                    file=sys.stderr,
                )
            else:
                print(f"{warning}", file=sys.stderr)
        if warnings and args.strict:
            failed += 1
            continue
        note = f", {_count(len(warnings), 'warning')}" if warnings else ""
        print(f"{spec}: ok ({checked.summary}{note})")
    if failed:
        print(
            f"fuzzkit: error: {failed} of {_count(len(args.files), 'file')} invalid",
            file=sys.stderr,
        )
        return EXIT_BAD_INPUT
    return EXIT_OK


# ---------------------------------------------------------------------------- info


def _variable_lines(
    var: Variable, kind: str, input_names: Sequence[str] = (), footprint: Footprint | None = None
) -> list[str]:
    head = f"  {var.name}  {range_text(var)}"
    if kind == "output":
        default = "NaN" if var.default is None else _num(var.default)
        if var.units and var.default is not None:
            default += f" {var.units}"
        head += f"  default {default}"
    lines = [head]
    width = max((len(t.name) for t in var.terms), default=0)
    if not var.terms:
        lines.append("    (no terms: used only in linear Sugeno terms)")
    for t in var.terms:
        names = (*input_names, "constant") if t.shape == "linear" else SHAPE_PARAMS[t.shape]
        params = " ".join(f"{n}={_num(v)}" for n, v in zip(names, t.params, strict=False))
        lines.append(f"    {t.name.ljust(width)}  {t.shape:<14} {params}")
        lower = footprint.lower(var.name, t.name) if footprint is not None else None
        if lower is not None:
            lt = lower.shape
            lparams = " ".join(
                f"{n}={_num(v)}" for n, v in zip(SHAPE_PARAMS[lt.shape], lt.params, strict=False)
            )
            scale = f" scale={_num(lower.scale)}" if lower.scale != 1.0 else ""
            lines.append(f"    {'':{width}}  lower: {lt.shape:<7} {lparams}{scale}")
    return lines


def _table_grid(rb: RuleBase) -> list[str] | None:
    grid = rule_grid(rb)
    if grid is None:
        return None
    corner = f"{grid.row_input}\\{grid.column_input}"
    first = max(len(x) for x in [corner, *grid.rows])
    width = max(len(x) for x in [*grid.columns, *(c for row in grid.cells for c in row)])
    lines = [
        "  " + " ".join([corner.ljust(first), *(x.ljust(width) for x in grid.columns)]).rstrip()
    ]
    for r, row in zip(grid.rows, grid.cells, strict=True):
        lines.append("  " + " ".join([r.ljust(first), *(c.ljust(width) for c in row)]).rstrip())
    return lines


def describe_rulebase(rb: RuleBase) -> str:
    """The text ``fuzzkit info`` prints."""
    src = f"  ({rb.source.path})" if rb.source is not None else ""
    lines = [f"{rb.name}{src}"]
    if rb.description:
        lines += textwrap.wrap(rb.description, 96, initial_indent="  ", subsequent_indent="  ")
    ops = rb.operators
    lines += [
        "",
        f"operators: and={ops.and_} or={ops.or_} implication={ops.implication} "
        f"aggregation={ops.aggregation}",
        f"defuzzifier: {rb.defuzzifier}    out_of_range: {rb.out_of_range}"
        + (f"    coverage: {rb.coverage}" if rb.coverage != "strict" else ""),
    ]
    fp = footprint_of(rb)
    if fp is not None:
        where = "continuous" if fp.resolution is None else f"{fp.resolution} samples"
        lines.append(
            f"interval type-2: type_reduction={fp.type_reduction} ({where}); upper terms, "
            "each lower function under its term"
        )
    lines += ["", "inputs:"]
    for var in rb.inputs:
        lines += _variable_lines(var, "input", footprint=fp)
    lines.append("outputs:")
    for var in rb.outputs:
        lines += _variable_lines(var, "output", rb.input_names, fp)
    lines.append("")
    grid = _table_grid(rb)
    shape = rule_grid(rb)
    if grid is not None and shape is not None:
        listed = "" if rb.table is not None else ", listed rule by rule in the file"
        lines.append(
            f"rules: {len(rb.rules)} (table: rows {shape.row_input}, columns "
            f"{shape.column_input} -> {shape.output}{listed})"
        )
        lines += grid
    else:
        lines.append(f"rules: {len(rb.rules)}")
        width = len(str(len(rb.rules)))
        for k, rule in enumerate(rb.rules, start=1):
            lines.append(f"  {str(k).rjust(width)}. {rule_sentence(rule)}")
    return "\n".join(lines)


def cmd_info(args: argparse.Namespace) -> int:
    """Describe a rule base; any other kind of file fuzzkit reads is named and summarised
    (a controller spec's rule base described after it)."""
    from fuzzkit.cli.file_kinds import KINDS, recognise

    try:
        kind, _ = recognise(args.rulebase)
    except ProblemsError:
        kind = KINDS[0]  # the rule-base reader says what is wrong
    if kind is KINDS[0]:
        print(describe_rulebase(_load(args.rulebase, "info")))
        return EXIT_OK
    checked = kind.check(args.rulebase, "")
    print(f"{args.rulebase}: {checked.summary}")  # the summary starts with the kind's name
    if kind.name == "controller spec":
        from fuzzkit.control.spec_reader import load_spec

        spec = load_spec(args.rulebase)
        print(spec_text(spec))
        if spec.rulebase is not None:
            print(f"\nrule base: {describe_rulebase(spec.rulebase)}")
    return EXIT_OK


def spec_text(spec: Any) -> str:
    """What ``fuzzkit info SPEC`` shows of a controller spec before its rule base: the period
    and surface, each axis's set point and gains, the limits, the safeguards, the sensor front
    end and the adaptation, every value as the controller uses it (defaults filled in)."""
    s, lim, sensor = spec.safety, spec.limits, spec.sensor
    surface = spec.surface.method
    if surface == "table":
        size = spec.surface.tolerance or spec.surface.resolution
        what = "tolerance" if spec.surface.tolerance is not None else "resolution"
        surface = f"table ({what} {size:g})"
    lines = [
        f"  {spec.kind}, period {spec.period_s * 1e3:g} ms ({1.0 / spec.period_s:g} Hz)"
        + (f", surface {surface}" if spec.kind == "fuzzy-pi" else "")
    ]
    for a in spec.axes:
        gains = f"kp {a.kp:g}, ki {a.ki:g}" + (f", kx {a.kx:g}" if a.kx is not None else "")
        lines.append(f"  axis {a.axis}: set point {a.setpoint_n:g} N; {gains}")
    lines.append(
        f"  limits: |u| <= {lim.correction_m:g} m per axis, |du| <= {lim.step_m:g} m per period"
    )
    engage = (
        "from the start"
        if s.engage_threshold_n is None
        else f"above {s.engage_threshold_n:g} N for {s.engage_samples} samples"
    )
    lines.append(
        f"  safety: limit {s.limit_n:g} N (trip after {s.trip_samples} samples, back off "
        f"{s.backoff_m:g} m at {s.backoff_speed_m_s:g} m/s); engage {engage}; spike gate "
        f"{s.spike_gate:g} N ({s.spike_confirm} in a row accepted)"
    )
    front = []
    if sensor.tare_samples:
        front.append(f"tare over the first {sensor.tare_samples} samples")
    if sensor.tool is not None:
        com = ", ".join(f"{c:g}" for c in sensor.tool.com_m)
        front.append(f"gravity compensation of {sensor.tool.mass_kg:g} kg at [{com}] m")
    if sensor.lowpass_hz is not None:
        front.append(f"low-pass {sensor.lowpass_hz:g} Hz")
    lines.append(f"  sensor front end: {'; '.join(front) or 'none (raw samples)'}")
    lines.append(f"  adaptation: {spec.adaptation.mode}")
    return "\n".join(lines)


# ---------------------------------------------------------------------------- eval


def _parse_inputs(
    rb: RuleBase, items: Sequence[str], option: str = "--input", every: bool = True
) -> dict[str, float]:
    """``NAME=VALUE`` items of ``option`` as input values; all inputs needed when ``every``."""
    from fuzzkit.errors import did_you_mean

    values: dict[str, float] = {}
    problems: list[str] = []
    for item in items:
        name, sep, text = item.partition("=")
        name = name.strip()
        if not sep:
            problems.append(f"{option} {item!r}: expected NAME=VALUE")
            continue
        if name not in rb.input_names:
            problems.append(
                f"{option} {item!r}: unknown input {name!r}"
                f"{did_you_mean(name, rb.input_names)}; expected one of "
                f"{', '.join(rb.input_names)}"
            )
            continue
        if name in values:
            problems.append(f"{option} {item!r}: input {name!r} given twice")
            continue
        try:
            values[name] = float(text)
        except ValueError:
            problems.append(f"{option} {item!r}: expected a number for {name!r}, got {text!r}")
    missing = [
        n
        for n in rb.input_names
        if every and n not in values and not any(p.startswith(f"{option} '{n}=") for p in problems)
    ]
    if missing:
        problems.append(
            f"missing --input for {', '.join(missing)} (rule base {rb.name!r} has "
            f"inputs {', '.join(rb.input_names)})"
        )
    if problems:
        raise EvaluationError("; ".join(problems))
    return values


def _read_points(
    rb: RuleBase, name: str, fh: TextIO
) -> tuple[list[str], list[list[str]], dict[str, list[float]]]:
    reader = csv.reader(fh)
    try:
        header = next(reader)
    except StopIteration:
        raise ProblemsError(
            [
                Problem(
                    Location(name),
                    "CSV file is empty; expected a header of "
                    f"input names ({', '.join(rb.input_names)})",
                )
            ]
        ) from None
    header = [h.strip() for h in header]
    problems: list[Problem] = []
    missing = [n for n in rb.input_names if n not in header]
    if missing:
        plural = "s" if len(missing) > 1 else ""
        problems.append(
            Problem(
                Location(name, 1),
                f"missing column{plural}"
                f" {', '.join(missing)} (expected a header naming every input: "
                f"{', '.join(rb.input_names)}; got {', '.join(header)})",
            )
        )
    clash = [n for n in rb.output_names if n in header]
    if clash:
        problems.append(
            Problem(
                Location(name, 1),
                f"column{'s' if len(clash) > 1 else ''} "
                f"{', '.join(clash)} would be overwritten by the output(s); "
                "rename them",
            )
        )
    dup = sorted({h for h in header if header.count(h) > 1})
    if dup:
        problems.append(Problem(Location(name, 1), f"duplicate column {', '.join(dup)}"))
    if problems:
        raise ProblemsError(problems)
    cols = {n: header.index(n) for n in rb.input_names}
    rows: list[list[str]] = []
    values: dict[str, list[float]] = {n: [] for n in rb.input_names}
    for row in _csv_rows(reader, name):
        line = reader.line_num
        if not row or all(not c.strip() for c in row):
            continue
        if len(row) != len(header):
            problems.append(
                Problem(Location(name, line), f"expected {len(header)} cells, got {len(row)}")
            )
            continue
        for n, j in cols.items():
            cell = row[j].strip()
            try:
                values[n].append(float(cell))
            except ValueError:
                problems.append(
                    Problem(Location(name, line), f"expected a number for {n!r}, got {cell!r}")
                )
                values[n].append(math.nan)
        rows.append(row)
        if len(problems) > 50:
            break  # the rest of a bad file would only repeat the same mistake
    if problems:
        raise ProblemsError(problems)
    return header, rows, values


def cmd_eval(args: argparse.Namespace) -> int:
    import numpy as np

    from fuzzkit.fuzzy.inference import Engine

    if args.png is not None and not args.explain:
        raise EvaluationError("--png draws the explanation: give --explain too")
    if args.explain and args.points is not None:
        raise EvaluationError("--explain explains one point: give --input NAME=VALUE, not --points")
    if args.png is not None:
        figure_format(args.png, "--png")
        check_output_path(args.png, "--png file")
    from fuzzkit.fuzzy.rule_view import DEFAULT_RULES

    if args.rules != DEFAULT_RULES and args.png is None:
        raise EvaluationError("--rules N is the number of rules --png draws: give --png too")
    rb = _load(args.rulebase, "eval")
    engine = Engine(rb)
    if args.points is None and args.explain:
        return _explain(rb, _parse_inputs(rb, args.inputs), args.json, args.png, args.rules)
    if args.points is None:
        point = _parse_inputs(rb, args.inputs)
        result = {k: shown_output(v, rb.output(k)) for k, v in engine.evaluate_point(point).items()}
        intervals = _centroid_intervals(rb, engine, point)
        if args.json:
            # JSON has no NaN: null stands for "no value" on both sides.
            def clean(values: dict[str, float]) -> dict[str, float | None]:
                return {k: (None if math.isnan(v) else v) for k, v in values.items()}

            doc: dict[str, Any] = {"inputs": clean(point), "outputs": clean(result)}
            if intervals:
                doc["intervals"] = {
                    k: [None if math.isnan(x) else x for x in v] for k, v in intervals.items()
                }
            print(json.dumps(doc, allow_nan=False))
        else:
            for k, v in result.items():
                lr = intervals.get(k)
                shown = "" if lr is None else f" (centroid interval [{lr[0]!r}, {lr[1]!r}])"
                print(f"{k} = {v!r}{shown}")
        return EXIT_OK
    if args.json:
        raise EvaluationError("--json applies to --input; --points writes CSV")
    if args.points == "-":
        header, rows, values = _read_points(rb, "<stdin>", sys.stdin)
    else:
        try:
            with open(args.points, newline="", encoding="utf-8") as fh:
                header, rows, values = _read_points(rb, args.points, fh)
        except IsADirectoryError:
            raise ProblemsError(
                [Problem(Location(args.points), "is a directory (expected a CSV file)")]
            ) from None
        except OSError as exc:
            raise ProblemsError(
                [Problem(Location(args.points), f"cannot read: {exc.strerror or exc}")]
            ) from None
        except UnicodeDecodeError:
            raise ProblemsError(
                [Problem(Location(args.points), "not UTF-8 text; expected a CSV file")]
            ) from None
    outputs = engine.evaluate({n: np.asarray(v, dtype=np.float64) for n, v in values.items()})
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow([*header, *rb.output_names])
    for i, row in enumerate(rows):
        got = [shown_output(float(outputs[n][i]), rb.output(n)) for n in rb.output_names]
        writer.writerow([*row, *map(repr, got)])
    sys.stdout.write(buf.getvalue())
    return EXIT_OK


def _centroid_intervals(
    rb: RuleBase, engine: Any, point: dict[str, float]
) -> dict[str, tuple[float, float]]:
    """An IT2 rule base's Karnik-Mendel interval ``(y_l, y_r)`` per output at ``point``, ends
    shown as the output is (:func:`~fuzzkit.fuzzy.describe.shown_output`); empty for type-1."""
    if footprint_of(rb) is None:
        return {}
    got = engine.centroid_intervals({k: [v] for k, v in point.items()})
    return {
        k: (shown_output(float(lo[0]), rb.output(k)), shown_output(float(hi[0]), rb.output(k)))
        for k, (lo, hi) in got.items()
    }


_BARS = " ▁▂▃▄▅▆▇█"


def _sparkline(mu: Any, width: int = 64) -> str:
    """The set's membership across the range as one line of block characters."""
    import numpy as np

    cols = np.array_split(np.asarray(mu, dtype=np.float64), width)
    return "".join(_BARS[round(float(c.max()) * (len(_BARS) - 1))] for c in cols)


def explanation_text(rb: RuleBase, data: Any) -> str:
    """What ``fuzzkit eval --explain`` prints for an :class:`~fuzzkit.fuzzy.explain.Explanation`."""
    lines = []
    for i in data.inputs:
        lows = i.lower_memberships
        fired = [
            f"{t} {_num(m)}" if lows is None else f"{t} [{_num(lows[t])}, {_num(m)}]"
            for t, m in i.memberships.items()
            if m > 0.0
        ]
        seen = "" if i.seen == i.value else f" (clamped to {_num(i.seen)})"
        lines.append(f"{i.name} = {_num(i.value)}{seen}: {', '.join(fired) or 'no term'}")
    ops = data.operators
    it2 = any(r.lower is not None for r in data.rules) or any(
        o.interval is not None for o in data.outputs
    )
    what = "firing interval [lower, upper]" if it2 else "strength"
    lines.append(
        f"rules that fire: {len(data.rules)} of {len(rb.rules)} ({what}: and={ops['and']} of "
        "the memberships, times the weight)"
    )
    lines += [
        f"  {r.strength:.4f}  #{r.index}: {r.text}"
        if r.lower is None
        else f"  [{r.lower:.4f}, {r.strength:.4f}]  #{r.index}: {r.text}"
        for r in data.rules
    ]
    for o in data.outputs:
        var = rb.output(o.name)
        active = ", ".join(f"{t} {_num(a)}" for t, a in o.activations.items() if a > 0.0)
        if len(o.y):
            upper = "upper " if o.mu_lower is not None else ""
            lines.append(
                f"{o.name}: {upper}aggregated set (implication {ops['implication']}, "
                f"aggregation {ops['aggregation']}); term levels {active or 'none'}"
            )
            lines.append(f"  {_num(var.low)} |{_sparkline(o.mu)}| {_num(var.high)}")
            if o.mu_lower is not None and o.lower_activations is not None:
                low_active = ", ".join(
                    f"{t} {_num(a)}" for t, a in o.lower_activations.items() if a > 0.0
                )
                lines.append(f"{o.name}: lower set; term levels {low_active or 'none'}")
                lines.append(f"  {_num(var.low)} |{_sparkline(o.mu_lower)}| {_num(var.high)}")
        else:
            values = ", ".join(f"{t} = {_num(v)}" for t, v in o.term_values.items())
            lines.append(f"{o.name}: Sugeno terms at this point: {values}; activations {active}")
        if o.interval is not None:
            lines.append(
                f"  centroid interval [{o.interval[0]!r}, {o.interval[1]!r}] (Karnik-Mendel)"
            )
        lines.append(f"  {o.name} = {o.value!r} ({o.defuzzifier})")
    return "\n".join(lines)


def _explain(
    rb: RuleBase, point: dict[str, float], as_json: bool, png: str | None, top: int
) -> int:
    from fuzzkit.fuzzy.explain import explain

    data = explain(rb, point)
    if png is not None:
        from fuzzkit.viz.explain_plot import write_explanation_png

        write_explanation_png(rb, data, png, top)
    if as_json:
        print(json.dumps(data.as_data(), allow_nan=False))
    else:
        print(explanation_text(rb, data))
        if png is not None:
            print(f"wrote {png}")
    return EXIT_OK


# ---------------------------------------------------------------------------- surface


def _csv_rows(reader: Any, name: str) -> Iterator[list[str]]:
    """The reader's rows; a malformed CSV (e.g. a field over the size limit) is a located error."""
    while True:
        try:
            yield next(reader)
        except StopIteration:
            return
        except csv.Error as exc:
            raise ProblemsError(
                [Problem(Location(name, reader.line_num), f"bad CSV: {exc}")]
            ) from exc


def _surface_inputs(text: str | None) -> tuple[str, ...] | None:
    """``--inputs e,de`` as names (checked against the rule base by surface_axes)."""
    if text is None:
        return None
    names = tuple(part.strip() for part in text.split(","))
    if len(names) != 2 or not all(names):
        raise EvaluationError(f"--inputs {text!r}: expected two input names, e.g. --inputs e,de")
    return names


def cmd_surface(args: argparse.Namespace) -> int:
    import numpy as np

    from fuzzkit.viz.surface import peak_grid, surface_axes, write_surface_png, write_surface_rrd

    if args.rrd is None and args.png is None:
        raise EvaluationError("nothing to write: give --rrd OUT.rrd and/or --png OUT.png")
    for option, path, suffix in (("--rrd", args.rrd, ".rrd"), ("--png", args.png, ".png")):
        if path is not None and Path(path).suffix.lower() != suffix:
            raise EvaluationError(f"{option} {path}: expected a file name ending in {suffix}")
    for option, path in (("--rrd", args.rrd), ("--png", args.png)):
        if path is not None:
            check_output_path(path, f"{option} file")
    rb = _load(args.rulebase, "surface")
    inputs = _surface_inputs(args.inputs)
    fixed = _parse_inputs(rb, args.fix, "--fix", every=False)
    axes = surface_axes(rb, args.output, inputs, fixed)  # every check before any file
    chosen = (axes.x.name, axes.y.name)
    if args.rrd is not None and len(rb.inputs) != 2:
        raise EvaluationError(
            f"--rrd needs a rule base with exactly 2 inputs; {rb.name!r} has {len(rb.inputs)} "
            f"({', '.join(rb.input_names)}); --png can span two and fix the others"
        )
    if args.rrd is not None and chosen != rb.input_names:
        raise EvaluationError(
            f"--rrd spans the inputs in declaration order ({', '.join(rb.input_names)}); "
            "--inputs applies to --png only"
        )
    if args.rrd is not None:
        write_surface_rrd(rb, args.rrd, args.resolution, axes.output)
        print(f"wrote {args.rrd}")
    if args.png is not None:
        write_surface_png(rb, args.png, args.resolution, axes.output, chosen, axes.fixed)
        print(f"wrote {args.png}")
    points, labels = peak_grid(rb, axes.output, chosen, axes.fixed)
    held = axes.fixed_text(rb)
    print(
        f"{axes.output} at the label peaks ({len(labels)} points"
        f"{', ' + held if held else ''}): min {_num(np.nanmin(points[:, 2]))}"
        f", max {_num(np.nanmax(points[:, 2]))}"
    )
    vx, vy = axes.x, axes.y
    z = points[:, 2].reshape(len(vx.terms), len(vy.terms))
    corner = f"{vx.name}\\{vy.name}"
    first = max(len(x) for x in [corner, *vx.term_names])
    # round first so that -1e-17 prints as +0.0000, not -0.0000
    cells = [[f"{round(float(v), 4) + 0.0:+.4f}" for v in row] for row in z]
    width = max(len(x) for x in [*vy.term_names, *(c for row in cells for c in row)])
    print("  " + " ".join([corner.ljust(first), *(t.rjust(width) for t in vy.term_names)]))
    for label, row in zip(vx.term_names, cells, strict=True):
        print("  " + " ".join([label.ljust(first), *(c.rjust(width) for c in row)]))
    return EXIT_OK


# ---------------------------------------------------------------------------- schema


def cmd_schema(args: argparse.Namespace) -> int:
    if args.controller:
        from fuzzkit.control.spec_schema import json_schema as controller_schema

        print(json.dumps(controller_schema(), indent=2))
        return EXIT_OK
    if args.scenario:
        from fuzzkit.studies.scenario_file import json_schema as scenario_schema

        print(json.dumps(scenario_schema(), indent=2))
        return EXIT_OK
    from fuzzkit.formats.schema import json_schema

    print(json.dumps(json_schema(), indent=2))
    return EXIT_OK
