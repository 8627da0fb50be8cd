"""The generated code on emulated Cortex-M microcontrollers (``make bench``; ``make embedded``
is the same run, which CI uses as a check).

Targets (issue 22): the controller step (two force axes, ``macvicar_whelan`` exact, float,
front end on) on Cortex-M4F in at most 2,500 instructions and 6 KiB of flash; the Q15 table
``eval`` on Cortex-M0 in at most 160 instructions. Needs ``arm-none-eabi-gcc`` and
``qemu-system-arm`` (``make embedded`` installs them as root); without them it says so.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

DRIVER = Path(__file__).parent / "embedded" / "run.py"


def main(argv: list[str]) -> int:
    spec = importlib.util.spec_from_file_location("embedded_run", DRIVER)
    if spec is None or spec.loader is None:
        raise RuntimeError(f"cannot load {DRIVER}")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclasses look their module up there
    spec.loader.exec_module(module)
    print(
        "targets: controller step on Cortex-M4F <= 2,500 instructions and <= 6 KiB flash; "
        "Q15 eval on Cortex-M0 <= 160 instructions"
    )
    status: int = module.main([])
    return status


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
