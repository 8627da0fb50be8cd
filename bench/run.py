"""Run every benchmark in this folder (``bench_*.py``) and print their tables.

Used by ``make bench``. Each module exposes ``main(argv)``; options it does not know are
ignored, so one command line serves all (``--peers-python`` for the engine benchmark).
"""

from __future__ import annotations

import importlib.util
import inspect
import sys
import time
import traceback
from pathlib import Path


def main() -> int:
    here = Path(__file__).parent
    argv = sys.argv[1:]
    only = [a for a in argv if not a.startswith("-") and not Path(a).exists()]
    failures = 0
    for path in sorted(here.glob("bench_*.py")):
        if only and path.stem.removeprefix("bench_") not in only:
            continue
        print(f"\n=== {path.stem} ===", flush=True)
        spec = importlib.util.spec_from_file_location(path.stem, path)
        if spec is None or spec.loader is None:
            continue
        module = importlib.util.module_from_spec(spec)
        start = time.perf_counter()
        try:
            spec.loader.exec_module(module)
            takes_argv = bool(inspect.signature(module.main).parameters)
            module.main(argv) if takes_argv else module.main()
        except SystemExit:
            pass
        except Exception:
            failures += 1
            traceback.print_exc()
        print(f"({path.stem}: {time.perf_counter() - start:.1f} s)", flush=True)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
