"""FMU target: the whole controller as an FMI 2.0 Co-Simulation FMU (``--target fmu``).

The controller's C is the C target's, rendered from the C target's templates (``extends``)
into ``sources/`` next to an FMI 2.0 wrapper (``fmi2.c.jinja``) and the three standard FMI 2.0
headers (BSD-2-Clause, Modelica Association; copied unchanged from the FMI Reference FMUs);
``modelDescription.xml`` declares the variables. :mod:`.package` then compiles the Linux x86-64
binary and zips the FMU deterministically (``Target.bundle``). It computes in double: FMI's
``fmi2Real`` is a double, and the FMU then equals the reference controller to rounding.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

from fuzzkit.codegen.backends.c.config import TARGET as C_TARGET
from fuzzkit.codegen.backends.fmu.package import bundle, open_controller

#: The standard headers of FMI 2.0 shipped with the sources (rendered verbatim: no Jinja in them).
FMI2_HEADERS = ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h")

TARGET = dataclasses.replace(
    C_TARGET,
    name="fmu",
    label="FMU (FMI 2.0 co-simulation)",
    folder=Path(__file__).parent,
    number_types=("double",),
    default_number_type="double",
    files={
        "controller": {
            "modelDescription.xml": "modelDescription.xml.jinja",
            "sources/{name}.h": "controller.h.jinja",
            "sources/{name}.c": "controller.c.jinja",
            "sources/{name}_fmi2.c": "fmi2.c.jinja",
            **{f"sources/{h}": h for h in FMI2_HEADERS},
        },
        "surface": {"sources/{name}.h": "exact.h.jinja", "sources/{name}.c": "exact.c.jinja"},
        # ... an interval type-2 rule base's (codegen.exact_type2)
        "surface_type2": {
            "sources/{name}.h": "exact.h.jinja",
            "sources/{name}.c": "exact_type2.c.jinja",
        },
        "surface_table": {
            "sources/{name}.h": "header.h.jinja",
            "sources/{name}.c": "source.c.jinja",
        },
    },
    open_controller=open_controller,
    extends="c",
    bundle=bundle,
    tunable_parameters=True,
)
