"""Which implementation runs the controller, per command x plant x controller kind (issue 37,
"done when"): the table of the issue's closing note, read from each run's own JSON or output.

Run: ``.venv/bin/python bench/impl_matrix.py [--plants planar,arm6] [--commands simulate]``
(prints a markdown table; the whole product takes several CPU-minutes, most of it tune and
MuJoCo). ``tests/test_impl_matrix.py`` runs a covering set of it in ``make test`` and the full
product in ``make verify``, and asserts that every cell is the generated controller (C where a
compiler exists) and never the reference.

Each cell is what the command itself reports: ``simulate --json`` and ``compare --json``
(``controller_impl`` of every run), ``sweep --out`` (its ``controller_impl`` column), ``tune``
(its ``controller:`` line, from the loop's own runs), ``stability --simulate --json`` (each
simulated cell's ``controller_impl``), the latency sweep (its map's ``controller_impl``, as
``bench/latency_sweep.py`` and the report print it) and ``report`` (every run in its
``runs.json``). ``make bench``'s loop tables (``bench/bench_loop.py``) print the same labels.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import io
import json
import re
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PLANTS = ("planar", "arm6", "mujoco", "mujoco-elastic")
#: E1 cut to its contact transient: first contact at about 1.9 s
SHORT_S = 2.6


def kinds(folder: Path) -> dict[str, list[str]]:
    """Controller kind -> the options that name it (the table spec is written to ``folder``)."""
    example = ROOT / "docs" / "examples" / "controller.yaml"
    table = folder / "spec_table.yaml"
    text = example.read_text(encoding="utf-8").rstrip("\n")
    table.write_text(text + "\nsurface: {method: table, resolution: 9}\n", encoding="utf-8")
    data = ROOT / "tests" / "data"
    gaussian, fis = str(data / "gaussian3x3.yaml"), str(data / "fis" / "gauss_outputs.fis")
    return {
        "PI": ["--controller", "pi"],
        "fuzzy-PI, exact surface": ["--controller", "fuzzy-pi"],
        "fuzzy-PI, table surface": ["--spec", str(table)],
        "Sugeno (sugeno_pi)": ["--controller", "fuzzy-pi", "--rulebase", "sugeno_pi"],
        "Gaussian output (gaussian3x3)": ["--controller", "fuzzy-pi", "--rulebase", gaussian],
        "renamed spec (spec_renamed)": ["--spec", str(data / "user" / "spec_renamed.yaml")],
        ".fis (gauss_outputs.fis)": ["--controller", "fuzzy-pi", "--rulebase", fis],
    }


def scenario(folder: Path) -> Path:
    """E1, cut to :data:`SHORT_S`, as a scenario file in ``folder``."""
    text = (ROOT / "fuzzkit" / "studies" / "scenarios" / "E1.yaml").read_text("utf-8")
    path = folder / "e1_short.yaml"
    path.write_text(re.sub(r"(?m)^duration_s: .*$", f"duration_s: {SHORT_S}", text), "utf-8")
    return path


class CommandFailed(RuntimeError):
    """A command of the matrix exited non-zero (its stderr is the message)."""


def _cli(argv: list[str]) -> str:
    from fuzzkit.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    if code != 0:
        raise CommandFailed(f"fuzzkit {' '.join(argv)}: exit {code}: {err.getvalue().strip()}")
    return out.getvalue()


def _simulate(scn: Path, opts: list[str], plant: str, folder: Path) -> list[str]:
    data = json.loads(_cli(["simulate", str(scn), *opts, "--plant", plant, "--json"]))
    return [str(data["controller_impl"])]


def _compare(scn: Path, opts: list[str], plant: str, folder: Path) -> list[str]:
    # compare runs PI and fuzzy-PI side by side: the rule base is what names the kind; on the
    # default gains (the matched protocol needs a small-signal gain, which sugeno_pi lacks)
    opts = [o for o in opts if o not in ("--controller", "pi", "fuzzy-pi")]
    argv = ["compare", str(scn), *opts, "--plant", plant, "--protocol", "default", "--json"]
    rows = json.loads(_cli(argv))
    return [str(r["controller_impl"]) for r in rows]


def _sweep(scn: Path, opts: list[str], plant: str, folder: Path) -> list[str]:
    table = folder / "sweep.csv"
    argv = ["sweep", str(scn), *opts, "--plant", plant, "--stiffness", "5,10"]
    _cli([*argv, "--out", str(table), "--workers", "1", "--quiet"])
    return [r["controller_impl"] for r in csv.DictReader(io.StringIO(table.read_text("utf-8")))]


def _tune(scn: Path, opts: list[str], plant: str, folder: Path) -> list[str]:
    gains = folder / "gains.yaml"
    argv = ["tune", str(scn), *opts, "--plant", plant, "--stiffness", "10", "--budget", "10"]
    printed = _cli([*argv, "--workers", "1", "--quiet", "--out", str(gains), "--force"])
    found = re.search(r"(?m)^controller: (.*)$", printed)
    if found is None:
        raise CommandFailed(f"tune printed no controller line:\n{printed}")
    return [found.group(1)]


def _stability(scn: Path, opts: list[str], plant: str, folder: Path) -> list[str]:
    argv = ["stability", str(scn), *opts, "--plant", plant, "--stiffness", "10"]
    data = json.loads(_cli([*argv, "--latency", "1:1", "--simulate", "--workers", "1", "--json"]))
    return [str(c["controller_impl"]) for c in data["cells"]]


def _option(opts: list[str], name: str, default: str) -> str:
    return opts[opts.index(name) + 1] if name in opts else default


def _latency(scn: Path, opts: list[str], plant: str, folder: Path) -> list[str]:
    from fuzzkit.studies.latency_sweep import stability_map

    controller = _option(opts, "--controller", "pi")
    rulebase = _option(opts, "--rulebase", "macvicar_whelan")
    m = stability_map(controller, (1.0,), (0,), rulebase, plant, duration_s=1.0)
    return [m.controller_impl]


def _report(scn: Path, opts: list[str], plant: str, folder: Path) -> list[str]:
    # the report runs PI and fuzzy-PI on E1-E3 itself: the kind is its rule base or spec
    from fuzzkit.control.gains import GainsEntry, write_gains
    from fuzzkit.studies.experiments import DEFAULT_GAINS

    gains = folder / "gains"
    gains.mkdir()
    for ctrl in ("pi", "fuzzy-pi"):
        write_gains(gains / f"{ctrl}.yaml", GainsEntry(ctrl, dict(DEFAULT_GAINS[ctrl])))
    opts = [o for o in opts if o not in ("--controller", "pi", "fuzzy-pi")]
    out = folder / "report"
    argv = ["report", "--out", str(out), "--plant", plant, "--quick", "--no-rrd", "--quiet"]
    _cli([*argv, "--gains-dir", str(gains), "--workers", "1", *opts])
    runs = json.loads((out / "runs.json").read_text("utf-8"))["runs"]
    return [str(r["controller_impl"]) for r in runs]


#: command -> how it runs and what it reports as the implementation of each of its runs
COMMANDS: dict[str, Callable[[Path, list[str], str, Path], list[str]]] = {
    "simulate": _simulate,
    "compare": _compare,
    "sweep": _sweep,
    "tune": _tune,
    "stability --simulate": _stability,
    "latency sweep": _latency,
    "report": _report,
}
#: what a command cannot take: compare and the latency sweep have no --spec, report's is a
#: section of its own (its own rows in the table)
NOT_TAKEN = {
    (command, kind)
    for command in ("compare", "latency sweep")
    for kind in ("fuzzy-PI, table surface", "renamed spec (spec_renamed)")
}


def implementations(command: str, plant: str, kind: str, folder: Path) -> list[str]:
    """What ran in each run of ``command`` on ``plant`` with ``kind``, as the command says."""
    return COMMANDS[command](scenario(folder), kinds(folder)[kind], plant, folder)


def generated_c(label: str) -> bool:
    """True when ``label`` (a run's ``controller_impl``) names the generated C controller."""
    return "generated C controller" in label and "reference" not in label


def cell(labels: list[str]) -> str:
    """A table cell: the distinct implementations, shortened to what they are."""
    short = []
    for label in labels:
        if generated_c(label):
            text = "generated C"
        elif "generated Python" in label:
            text = "generated Python"
        elif "reference" in label:
            text = "REFERENCE"
        else:
            text = label
        loop = re.search(r"\((compiled loop|python loop)\)", label)
        text += f" ({loop.group(1)})" if loop else ""
        if text not in short:
            short.append(text)
    return ", ".join(short)


def main(argv: list[str] | None = None) -> int:
    """Run the matrix and print it as markdown; exit 1 when a cell is not the generated C."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--plants", default=",".join(PLANTS))
    parser.add_argument("--commands", default=",".join(COMMANDS), help="comma-separated")
    args = parser.parse_args(argv)
    plants = args.plants.split(",")
    commands = args.commands.split(",")
    ok = True
    with tempfile.TemporaryDirectory() as tmp:
        names = list(kinds(Path(tmp)))
        print("| command | plant | " + " | ".join(names) + " |")
        print("|---|---|" + "---|" * len(names))
        for command in commands:
            for plant in plants:
                cells = []
                for kind in names:
                    if (command, kind) in NOT_TAKEN:
                        cells.append("(not taken)")
                        continue
                    folder = Path(tempfile.mkdtemp(dir=tmp))
                    try:
                        labels = implementations(command, plant, kind, folder)
                    except CommandFailed as exc:
                        cells.append(f"FAILED: {exc}".replace("|", "/")[:200])
                        ok = False
                        continue
                    ok = ok and all(generated_c(x) for x in labels)
                    cells.append(cell(labels))
                print(f"| {command} | {plant} | " + " | ".join(cells) + " |", flush=True)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
