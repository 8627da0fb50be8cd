"""Run by the interop tests with the `.venv-interop` Python (pyfuzzylite 8 pins numpy<2).

    python pyfuzzylite_eval.py eval ENGINE.fll POINTS.json   -> {"output": [values...]} on stdout
    python pyfuzzylite_eval.py export ENGINE.fll             -> the engine as pyfuzzylite writes FLL
    python pyfuzzylite_eval.py version                       -> pyfuzzylite's version

POINTS.json is {"input name": [values...]}; missing outputs are NaN, written as null.
Integral defuzzifiers keep the resolution written in the file.
"""

from __future__ import annotations

import json
import math
import sys

import fuzzylite as fl
import numpy as np


def main() -> None:
    verb = sys.argv[1]
    if verb == "version":
        sys.stdout.write(fl.__version__ + "\n")
        return
    path = sys.argv[2]
    engine = fl.FllImporter().from_file(path)
    if verb == "export":
        sys.stdout.write(fl.FllExporter().to_string(engine))
        return
    with open(sys.argv[3], encoding="utf-8") as fh:
        points = json.load(fh)
    for var in engine.input_variables:
        var.value = np.asarray(points[var.name], dtype=float)
    engine.process()
    out = {}
    for var in engine.output_variables:
        values = np.atleast_1d(np.asarray(var.value, dtype=float))
        out[var.name] = [None if math.isnan(v) else float(v) for v in values]
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    main()
