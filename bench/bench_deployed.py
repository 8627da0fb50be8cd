"""Loop speed with the deployed arithmetic (issue 28 item 7): real-time factors of the default
compiled loop, E1-E3 x PI / fuzzy-PI on ``arm6`` and ``planar``, plus the user-style specs.

Run: ``.venv/bin/python bench/bench_deployed.py`` (about a minute). CPU time of the loop alone
(``RunResult.real_time_factor``), best of 5 runs after one warm-up run. Targets: arm6 >= 1000x,
planar >= 400x.
"""

from __future__ import annotations

import sys
from pathlib import Path

TARGETS = {"arm6": 1000.0, "planar": 400.0}
USER_SPECS = ("nonuniform5", "renamed", "gauss_prod", "user_pi")


def rows() -> list[tuple[str, str, float, float]]:
    """``(case, what ran, rtf, target)`` per case."""
    from fuzzkit.loop.spec import RunSpec
    from fuzzkit.studies.batch import run_spec

    root = Path(__file__).resolve().parent.parent / "tests" / "data" / "user"
    cases = [
        (f"{exp} {plant} {ctrl}", RunSpec(exp, ctrl, plant=plant), plant)
        for plant in TARGETS
        for exp in ("E1", "E2", "E3")
        for ctrl in ("pi", "fuzzy-pi")
    ]
    cases += [
        (
            f"E1 {plant} spec {name}",
            RunSpec("E1", plant=plant, controller_spec=str(root / f"spec_{name}.yaml")),
            plant,
        )
        for plant in TARGETS
        for name in USER_SPECS
    ]
    out = []
    for label, spec, plant in cases:
        try:
            first = run_spec(spec)
        except Exception as exc:  # a benchmark row says what failed
            out.append((label, f"failed: {str(exc).splitlines()[0][:60]}", 0.0, TARGETS[plant]))
            continue
        best = max(run_spec(spec).real_time_factor for _ in range(5))
        out.append((label, f"{first.loop}: {first.controller_impl[:48]}", best, TARGETS[plant]))
    return out


def main() -> int:
    print(f"{'case':32} {'rtf':>9} {'target':>7}  what ran")
    for label, what, rtf, target in rows():
        flag = "" if rtf >= target else "  BELOW"
        print(f"{label:32} {rtf:9.0f} {target:7.0f}  {what}{flag}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
