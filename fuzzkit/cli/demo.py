"""``fuzzkit demo``: the main job on the shipped defaults, as ``make demo`` runs it.

It is nothing but a sequence of ordinary ``fuzzkit`` commands, each printed before it runs,
so an engineer can copy any step and vary it.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path


def demo_steps(out: Path) -> list[list[str]]:
    """The commands of the demo, in order, writing their files under ``out``."""
    from fuzzkit.formats.registry import available

    return [
        ["validate", *available()],
        ["info", "macvicar_whelan"],
        [
            "surface",
            "macvicar_whelan",
            "--rrd",
            str(out / "macvicar_whelan_surface.rrd"),
            "--png",
            str(out / "macvicar_whelan_surface.png"),
        ],
        ["compile", "macvicar_whelan", "--target", "c", "--out", str(out / "c"), "--verify"],
        [
            "compile",
            "macvicar_whelan",
            "--target",
            "c",
            "--type",
            "q15",
            "--out",
            str(out / "c_q15"),
            "--verify",
        ],
        [
            "compile",
            "macvicar_whelan",
            "--target",
            "python",
            "--out",
            str(out / "python"),
            "--verify",
        ],
        ["compare", "E1", "--rrd-dir", str(out)],
        # what ships is what runs: the whole controller (front end, safety logic, limits)
        # generated as C and run inside the closed loop
        [
            "simulate",
            "E1",
            "--controller",
            "fuzzy-pi",
            "--controller-impl",
            "c",
            "--png",
            str(out / "E1_fuzzy-pi_generated_c.png"),
        ],
    ]


def _run(args: argparse.Namespace) -> int:
    from fuzzkit.cli import EXIT_BROKEN_PIPE, EXIT_INTERRUPTED, main

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for step in demo_steps(out):
        print(f"\n$ fuzzkit {' '.join(step)}", flush=True)
        start = time.perf_counter()
        code = main(step)
        print(f"  ({time.perf_counter() - start:.1f} s)", flush=True)
        if code in (EXIT_INTERRUPTED, EXIT_BROKEN_PIPE):
            return code  # Ctrl-C or a closed pipe: the step has said so, or no one listens
        if code != 0:
            print(f"demo: step failed with exit code {code}")
            return code
    print(
        f"\ndemo: done; recordings, figures and generated sources are in {out}/ "
        "(open the .rrd files with `rerun FILE.rrd`)"
    )
    return 0


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser(
        "demo",
        help="run the main job on the shipped defaults (make demo)",
        description="Validate the shipped rule bases, describe macvicar_whelan, draw its "
        "control surface, compile it to C (float and Q15) and Python with --verify, and "
        "compare PI with fuzzy-PI on E1 with recordings. Each step is an ordinary fuzzkit "
        "command, printed before it runs, so any step can be copied and varied.",
        epilog="examples:\n  fuzzkit demo\n  fuzzkit demo --out /tmp/demo && rerun /tmp/demo/*.rrd",
    )
    p.add_argument("--out", default="demo-out", help="folder for the files it writes")
    p.set_defaults(handler=_run)
