"""Integer means integer, and every header lists what its code calls (issue 22 item 3).

The Q15 table with its fuzzy-PI compiles for Cortex-M0 and M3 into objects that reference no
floating-point routine, and an image linked from them *without* ``--gc-sections`` holds none
either (``arm-none-eabi-nm``). Every generated C object, built by the host compiler at several
optimisation levels (and for the Cortex-M4F), calls only the functions its header lists on its
``External functions:`` line (``nm -u``): the compiler's own ``memset`` for zeroing included.
"""

from __future__ import annotations

import functools
import os
import re
import shutil
import subprocess
from collections.abc import Callable
from pathlib import Path

import pytest
from _codegen_util import CC, needs_cc

from fuzzkit.codegen.method import compile_rulebase
from fuzzkit.control.spec_reader import load_spec
from fuzzkit.formats.registry import load
from fuzzkit.loop.controller_code import generate

REPO = Path(__file__).parent.parent
DATA = Path(__file__).parent / "data"
ARM_GCC = shutil.which("arm-none-eabi-gcc")
ARM_NM = shutil.which("arm-none-eabi-nm")
#: CI installs the toolchain before the suite (.ci/run: make embedded-toolchain), so there a
#: missing toolchain is a failure, never a skip: the float-free claim must be checked in CI.
IN_CI = os.environ.get("CI", "").lower() == "true"
ARM_MISSING = (
    "the arm-none-eabi toolchain is not installed (apt-get install "
    "--no-install-recommends gcc-arm-none-eabi libnewlib-arm-none-eabi; CI has it)"
)


@pytest.fixture
def arm_toolchain() -> tuple[str, str]:
    """arm-none-eabi-gcc and -nm; skip without them, except in CI (CI=true), where it fails."""
    if ARM_GCC is None or ARM_NM is None:
        if IN_CI:
            pytest.fail(f"CI=true but {ARM_MISSING}: run `make embedded-toolchain` first")
        pytest.skip(ARM_MISSING)
    return ARM_GCC, ARM_NM


ARM_CPUS = {
    "m0": ("-mcpu=cortex-m0", "-mthumb"),
    "m3": ("-mcpu=cortex-m3", "-mthumb"),
    "m4f": ("-mcpu=cortex-m4", "-mthumb", "-mfpu=fpv4-sp-d16", "-mfloat-abi=hard"),
}
FLAGS = ("-std=c99", "-ffp-contract=off", "-Wall", "-Wextra", "-Werror", "-pedantic")
#: libgcc's soft-float and float-conversion routines (ARM EABI names and GCC's generic ones)
FLOAT_HELPER = re.compile(r"^(__aeabi_[fd]\w+|__aeabi_\w*2[fd]|__\w*[sdt]f\w*)$")
EXTERNAL = re.compile(r"External functions: ([^.]*)\.")


def _write(folder: Path, files: dict[str, str]) -> list[Path]:
    for rel, text in files.items():
        (folder / rel).write_text(text)
    return [folder / rel for rel in files if rel.endswith(".c")]


def _undefined(nm: str, obj: Path) -> set[str]:
    out = subprocess.run([nm, "-u", str(obj)], capture_output=True, text=True, check=True).stdout
    return {line.split()[-1] for line in out.splitlines() if line.strip()}


def _listed(header: str) -> set[str]:
    match = EXTERNAL.search(" ".join(line.strip(" *") for line in header.splitlines()))
    assert match is not None, "the header has no 'External functions:' line"
    names = {n.strip() for n in match.group(1).split(",")}
    return set() if names == {"none"} else names


def _q15_files() -> dict[str, str]:
    rb = load("macvicar_whelan")
    return dict(compile_rulebase(rb, "c", "q15", method="table", resolution=33).files)


def _table(number_type: str) -> dict[str, str]:
    mw = load("macvicar_whelan")
    return dict(compile_rulebase(mw, "c", number_type, method="table", resolution=33).files)


def _exact(name: str, number_type: str) -> dict[str, str]:
    return dict(compile_rulebase(load(name), "c", number_type, method="exact").files)


def _controller(example: str, number_type: str) -> dict[str, str]:
    return generate(load_spec(REPO / "docs" / "examples" / example), "c", number_type)


#: Every kind of generated C: tables (3 types), exact (2 types, libm too), controllers; each
#: built on first use (:func:`built`), so collecting the module builds nothing.
KINDS: dict[str, Callable[[], dict[str, str]]] = {
    "table-float": lambda: _table("float"),
    "table-double": lambda: _table("double"),
    "table-q15": _q15_files,
    "exact-float": lambda: _exact("macvicar_whelan", "float"),
    "exact-double": lambda: _exact("macvicar_whelan", "double"),
    "exact-gaussian-float": lambda: _exact("three_input", "float"),
    "exact-gaussian-outputs-float": lambda: _exact(str(DATA / "gaussian3x3.yaml"), "float"),
    "controller-fuzzy-float": lambda: _controller("controller.yaml", "float"),
    "controller-pi-double": lambda: _controller("controller_pi.yaml", "double"),
}


@functools.cache
def built(kind: str) -> dict[str, str]:
    """The generated files of ``kind`` (:data:`KINDS`), built once per process."""
    return KINDS[kind]()


def _check_listed(tmp_path: Path, files: dict[str, str], compiler: list[str], nm: str) -> None:
    sources = _write(tmp_path, files)
    generated = {Path(rel).stem for rel in files if rel.endswith(".c")}
    for src in sources:
        obj = src.with_suffix(".o")
        subprocess.run(
            [*compiler, *FLAGS, "-c", str(src), "-o", str(obj), f"-I{tmp_path}"],
            check=True,
            capture_output=True,
        )
        # a controller calls its sibling unit (the fuzzy-PI surface): that is not a library
        called = {s for s in _undefined(nm, obj) if not any(s.startswith(g) for g in generated)}
        listed = _listed(files[src.with_suffix(".h").name])
        assert called <= listed, f"{src.name} ({' '.join(compiler)}): {called - listed} unlisted"


@needs_cc
@pytest.mark.parametrize("level", ["-O0", "-O2", "-O3", "-Os"])
@pytest.mark.parametrize("artefact", sorted(KINDS))
def test_host_objects_call_only_what_the_header_lists(
    tmp_path: Path, artefact: str, level: str
) -> None:
    assert CC is not None
    _check_listed(tmp_path, built(artefact), [*CC, level], shutil.which("nm") or "nm")


def test_the_headers_list_memset_and_the_math_functions() -> None:
    # the float code's memset is real: gcc -O3 and the ARM builds call it (checked above)
    assert _listed(built("exact-float")["macvicar_whelan.h"]) == {"memset"}
    # float code computes exp, log, pow and erfc itself (the same bits with any C library)
    assert _listed(built("exact-gaussian-float")["three_input.h"]) == {"memset", "fabsf"}
    gaussian_outputs = built("exact-gaussian-outputs-float")["gaussian3x3.h"]
    assert _listed(gaussian_outputs) == {"memset", "fabsf", "sqrtf"}
    assert _listed(built("exact-double")["macvicar_whelan.h"]) == {"memset"}
    assert _listed(built("table-q15")["macvicar_whelan.h"]) == set()
    ctl = built("controller-fuzzy-float")["e1_fuzzy_controller.h"]
    assert _listed(ctl) == {"memset", "sqrtf", "e1_fuzzy_surface_eval"}


@pytest.mark.parametrize(
    "artefact",
    ["table-float", "exact-float", "exact-gaussian-outputs-float", "controller-fuzzy-float"],
)
def test_cortex_m4f_objects_call_only_what_the_header_lists(
    tmp_path: Path, artefact: str, arm_toolchain: tuple[str, str]
) -> None:
    arm_gcc, arm_nm = arm_toolchain
    _check_listed(tmp_path, built(artefact), [arm_gcc, *ARM_CPUS["m4f"], "-O2"], arm_nm)


@pytest.mark.parametrize("cpu", ["m0", "m3"])
def test_q15_links_no_floating_point_routine_without_gc_sections(
    tmp_path: Path, cpu: str, arm_toolchain: tuple[str, str]
) -> None:
    arm_gcc, arm_nm = arm_toolchain
    files = _q15_files()
    assert "float" not in files["macvicar_whelan.c"] and "double" not in files["macvicar_whelan.c"]
    (src,) = _write(tmp_path, files)
    obj = tmp_path / "q15.o"
    subprocess.run([arm_gcc, *ARM_CPUS[cpu], *FLAGS, "-O2", "-c", str(src), "-o", str(obj)],
                   check=True, capture_output=True)  # fmt: skip
    called = _undefined(arm_nm, obj)
    # the only routine: Cortex-M0's 32x32->64 multiply (integer) for the fuzzy-PI's gains
    assert called <= {"__aeabi_lmul"}
    assert (called == {"__aeabi_lmul"}) == (cpu == "m0")
    # linked into a whole image that calls eval and the fuzzy-PI, every section kept
    main = tmp_path / "main.c"
    main.write_text(
        '#include "macvicar_whelan.h"\n'
        "volatile int sink[3];\n"
        "void _start(void);\n"
        "void _start(void)\n{\n"
        "    int16_t in[2], out[1];\n    macvicar_whelan_fpi_t c;\n"
        "    in[0] = (int16_t)sink[0];\n    in[1] = (int16_t)sink[1];\n"
        "    macvicar_whelan_eval(in, out);\n"
        "    macvicar_whelan_fpi_init(&c, 52429, 13107, 3277, -16384, 16384);\n"
        "    sink[2] = out[0] + macvicar_whelan_fpi_step(&c, in[0], in[1]);\n"
        "    for (;;) {\n    }\n}\n"
    )
    elf = tmp_path / "image.elf"
    subprocess.run(
        [arm_gcc, *ARM_CPUS[cpu], *FLAGS, "-O2", "-nostartfiles", "--specs=nosys.specs",
         "-o", str(elf), str(main), str(src), f"-I{tmp_path}"],
        check=True, capture_output=True,
    )  # fmt: skip
    out = subprocess.run([arm_nm, str(elf)], capture_output=True, text=True, check=True).stdout
    symbols = {line.split()[-1] for line in out.splitlines() if line.strip()}
    assert "macvicar_whelan_fpi_step" in symbols  # the probe did link the code
    helpers = sorted(s for s in symbols if FLOAT_HELPER.match(s))
    assert helpers == []


def test_the_float_helper_pattern_matches_what_it_must() -> None:
    # the check above is worth something only if the pattern catches the soft-float routines
    for name in ("__aeabi_fadd", "__aeabi_dmul", "__aeabi_i2f", "__aeabi_ui2d", "__addsf3",
                 "__muldf3", "__floatsisf", "__fixdfsi", "__extendsfdf2"):  # fmt: skip
        assert FLOAT_HELPER.match(name), name
    for name in ("__aeabi_lmul", "__aeabi_idiv", "__aeabi_uidivmod", "memset", "__aeabi_llsr"):
        assert not FLOAT_HELPER.match(name), name
