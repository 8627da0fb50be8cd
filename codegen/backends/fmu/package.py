"""Build the FMU: compile the Linux x86-64 binary from the rendered sources, then zip it all.

The archive is reproducible: entries in sorted order, every timestamp 1980-01-01 00:00, fixed
permissions, deflate; the binary is compiled without debug information from relative paths,
so the same spec and compiler give the same bytes.
"""

from __future__ import annotations

import io
import platform
import tempfile
import zipfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from fuzzkit.codegen.backends.c.run import CompiledController
from fuzzkit.codegen.toolchain import STRICT_FLAGS, find_compiler, run_compiler
from fuzzkit.errors import CodegenError, ToolchainError

#: FMI 2.0's name of the one platform this machine builds a binary for.
PLATFORM = "linux64"
#: The binary's build: the strict flags of every generated C, no FMA contraction (so the
#: FMU computes what the reference's double computes), only the fmi2 functions exported.
FLAGS = (*STRICT_FLAGS, "-O2", "-ffp-contract=off", "-fPIC", "-shared", "-fvisibility=hidden")
_ZIP_TIME = (1980, 1, 1, 0, 0, 0)
SOURCES = "sources/"


def _check_platform() -> None:
    if platform.system() != "Linux" or platform.machine() not in ("x86_64", "AMD64"):
        raise CodegenError(
            f"the FMU's binary is built for {PLATFORM} (Linux x86-64) only; this is "
            f"{platform.system()} {platform.machine()}: build the sources/ of an FMU made "
            "on Linux with your platform's compiler instead"
        )


def build_binary(files: Mapping[str, str], model_identifier: str) -> bytes:
    """Compile ``sources/*.c`` of ``files`` into the FMU's shared library; its bytes.

    Raises
    ------
    ToolchainError
        No C compiler, or the sources do not compile.
    """
    cc = find_compiler()
    if cc is None:
        raise ToolchainError("no C compiler found (set $CC or install cc, gcc or clang)")
    with tempfile.TemporaryDirectory(prefix="fuzzkit-fmu-") as tmp:
        folder = Path(tmp)
        sources = []
        for rel, text in files.items():
            if rel.startswith(SOURCES):
                name = rel[len(SOURCES) :]
                (folder / name).write_text(text, encoding="utf-8")
                if name.endswith(".c"):
                    sources.append(name)
        out = f"{model_identifier}.so"
        run_compiler([*cc, *FLAGS, "-o", out, *sorted(sources), "-lm"], folder, "the FMU")
        return (folder / out).read_bytes()


def zip_bytes(entries: Mapping[str, bytes]) -> bytes:
    """A zip of ``{path: bytes}``: sorted, fixed timestamps and permissions, deflated."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        for path in sorted(entries):
            info = zipfile.ZipInfo(path, date_time=_ZIP_TIME)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            info.create_system = 3  # Unix: the permissions above are meant as such
            zf.writestr(info, entries[path])
    return buf.getvalue()


def bundle(files: Mapping[str, str], model_identifier: str) -> bytes:
    """The FMU's bytes: ``files`` (modelDescription.xml, sources/) plus the compiled binary
    ``binaries/linux64/<model_identifier>.so`` (``Target.bundle``).

    Raises
    ------
    CodegenError
        Not on Linux x86-64 (the only binary this builds).
    ToolchainError
        No C compiler, or the sources do not compile.
    """
    _check_platform()
    entries = {rel: text.encode("utf-8") for rel, text in files.items()}
    entries[f"binaries/{PLATFORM}/{model_identifier}.so"] = build_binary(files, model_identifier)
    return zip_bytes(entries)


def open_controller(files: Mapping[str, str], module: str, number_type: str) -> Any:
    """The FMU's controller sources (without the fmi2 wrapper) compiled and loaded, for
    ``fuzzkit compile --verify`` (``Target.open_controller``)."""
    controller = {
        rel[len(SOURCES) :]: text
        for rel, text in files.items()
        if rel.startswith(SOURCES) and not rel.endswith("_fmi2.c")
    }
    return CompiledController(controller, module, number_type)
