"""Latency stability boundary of PI and fuzzy-PI (docs/simulation.md, Latency).

Prints the stable/unstable map and writes docs/figures/latency_boundary.png:
    .venv/bin/python bench/latency_sweep.py [--out PNG]
"""

from __future__ import annotations

import argparse

from fuzzkit.studies.latency_sweep import stability_map
from fuzzkit.viz.latency import write_stability_png

FACTORS = (1.0, 2.0, 3.0, 4.0, 6.0, 8.0)
DELAYS = tuple(range(9))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", default="docs/figures/latency_boundary.png")
    args = parser.parse_args()
    maps = [stability_map(c, FACTORS, DELAYS) for c in ("pi", "fuzzy-pi")]
    head = f"{'controller':<10}{'factor':>7}  stable at delay (periods) "
    print(head + " ".join(map(str, DELAYS)))
    for m in maps:
        for factor, row in zip(m.factors, m.stable, strict=True):
            cells = " ".join("+" if ok else "." for ok in row)
            bound = m.boundary()[factor]
            print(f"{m.controller:<10}{factor:>7g}  {' ' * 26}{cells}   boundary {bound}")
    for m in maps:
        print(f"{m.controller}: {m.controller_impl}")
    print(f"wrote {write_stability_png(maps, args.out)}")


if __name__ == "__main__":
    main()
