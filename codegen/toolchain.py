"""Compile generated C with the system compiler and load it with ctypes (tests, --verify, bench).

The generated files are written to a private temporary folder together with a tiny batch
harness (``fuzzkit_batch_eval``, ``fuzzkit_fpi_run``) so that 1e5 points cost one ctypes call,
not 1e5. Nothing here is part of the generated code.
"""

from __future__ import annotations

import ctypes
import functools
import hashlib
import os
import shlex
import shutil
import subprocess
import tempfile
from collections.abc import Mapping, Sequence
from pathlib import Path
from types import TracebackType
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.errors import ToolchainError

#: Flags every generated file must compile cleanly with.
STRICT_FLAGS = ("-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic")
SANITIZE_FLAGS = ("-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-g")

_CTYPES: dict[str, Any] = {
    "float": ctypes.c_float,
    "double": ctypes.c_double,
    "q15": ctypes.c_int16,
}
_NUMPY = {"float": np.float32, "double": np.float64, "q15": np.int16}


def find_compiler(preferred: str | None = None) -> list[str] | None:
    """The C compiler command: ``preferred``, else ``$CC``, else cc, gcc or clang on PATH."""
    candidates: list[str] = []
    if preferred:
        candidates.append(preferred)
    elif os.environ.get("CC"):
        candidates.append(os.environ["CC"])
    else:
        candidates.extend(["cc", "gcc", "clang"])
    for cand in candidates:
        argv = shlex.split(cand)
        if argv and shutil.which(argv[0]):
            return argv
    return None


def _c_type(number_type: str) -> str:
    return {"float": "float", "double": "double", "q15": "int16_t"}[number_type]


def harness_source(name: str, number_type: str, n_inputs: int, n_outputs: int, fpi: bool) -> str:
    """C source of the batch helpers compiled next to the generated code."""
    t = _c_type(number_type)
    text = f"""#include "{name}.h"

void fuzzkit_batch_eval(const {t} *in, {t} *out, long n);
void fuzzkit_batch_eval(const {t} *in, {t} *out, long n)
{{
    long k;
    for (k = 0; k < n; k++) {{
        {name}_eval(in + k * {n_inputs}, out + k * {n_outputs});
    }}
}}
"""
    if fpi:
        g = "int32_t" if number_type == "q15" else t  # Q15 fpi_init takes codes
        text += f"""
void fuzzkit_fpi_run(const {g} *gains, const {t} *sp, const {t} *meas, {t} *u, long n,
                     unsigned long *faults);
void fuzzkit_fpi_run(const {g} *gains, const {t} *sp, const {t} *meas, {t} *u, long n,
                     unsigned long *faults)
{{
    {name}_fpi_t c;
    long k;
    {name}_fpi_init(&c, gains[0], gains[1], gains[2], gains[3], gains[4]);
    for (k = 0; k < n; k++) {{
        u[k] = {name}_fpi_step(&c, sp[k], meas[k]);
        faults[k] = c.faults;
    }}
}}
"""
    return text


def run_compiler(
    argv: Sequence[str], cwd: Path, what: str = "generated C"
) -> subprocess.CompletedProcess[str]:
    """Run a compiler command; ToolchainError with its full output when it fails."""
    try:
        proc = subprocess.run(
            list(argv), cwd=cwd, capture_output=True, text=True, timeout=300, check=False
        )
    except OSError as exc:
        raise ToolchainError(f"cannot run {argv[0]}: {exc}") from exc
    except subprocess.TimeoutExpired as exc:
        raise ToolchainError(f"{argv[0]} timed out compiling {what}") from exc
    if proc.returncode != 0:
        raise ToolchainError(
            f"compiling {what} failed ({shlex.join(argv)}), exit {proc.returncode}:\n"
            + (proc.stderr or proc.stdout).strip()
        )
    return proc


def build_library(
    folder: Path,
    files: Mapping[str, str],
    name: str,
    *,
    compiler: Sequence[str] | None = None,
    flags: Sequence[str] = (*STRICT_FLAGS, "-O2"),
    libs: Sequence[str] = ("-lm",),
) -> Any:
    """Write ``files`` into ``folder``, compile their ``.c`` files into ``libNAME.so`` there and
    load it (a ``ctypes.CDLL``; it stays mapped after the folder is removed).

    Raises
    ------
    ToolchainError
        No C compiler found, or the code does not compile.
    """
    cc = list(compiler) if compiler else find_compiler()
    if cc is None:
        raise ToolchainError(
            "no C compiler found (set $CC or install cc, gcc or clang) to compile generated C"
        )
    for rel, text in files.items():
        (folder / rel).write_text(text, encoding="utf-8")
    sources = [rel for rel in files if rel.endswith(".c")]
    lib = folder / f"lib{name}.so"
    run_compiler([*cc, *flags, "-shared", "-fPIC", "-o", str(lib), *sources, *libs], folder)
    return ctypes.CDLL(str(lib))


@functools.cache
def compiler_identity(cc: tuple[str, ...]) -> str:
    """``cc --version``'s first line (the compiler's name and version), or ``""``."""
    try:
        proc = subprocess.run(
            [*cc, "--version"], capture_output=True, text=True, timeout=30, check=False
        )
    except (OSError, subprocess.TimeoutExpired):
        return ""
    return (proc.stdout or proc.stderr).splitlines()[0] if (proc.stdout or proc.stderr) else ""


def library_cache_dir() -> Path:
    """Where compiled controllers are kept: ``$FUZZKIT_CACHE_DIR/controllers``, else
    ``$XDG_CACHE_HOME/fuzzkit/controllers`` (``~/.cache/fuzzkit/controllers``). Deleting the
    folder is safe: what is missing is compiled again."""
    env = os.environ.get("FUZZKIT_CACHE_DIR")
    base = Path(env) if env else Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return base / "controllers" if env else base / "fuzzkit" / "controllers"


def library_cache_path(
    files: Mapping[str, str],
    name: str,
    cc: Sequence[str],
    flags: Sequence[str],
    libs: Sequence[str],
) -> Path:
    """Where :func:`cached_library` keeps the library of ``files`` built by ``cc``."""
    from fuzzkit import __version__

    digest = hashlib.sha256(compiler_identity(tuple(cc)).encode() + b"\0")
    digest.update(f"fuzzkit {__version__}\0{list(cc)!r}\0{list(flags)!r}\0{list(libs)!r}".encode())
    for rel in sorted(files):
        digest.update(rel.encode() + b"\0" + files[rel].encode() + b"\0")
    return library_cache_dir() / f"{name}-{digest.hexdigest()[:32]}.so"


def cached_library(
    files: Mapping[str, str],
    name: str,
    *,
    compiler: Sequence[str] | None = None,
    flags: Sequence[str] = (*STRICT_FLAGS, "-O2"),
    libs: Sequence[str] = ("-lm",),
) -> Any:
    """:func:`build_library` through an on-disk cache keyed by the sources, the compiler
    command and its ``--version``, the flags and the fuzzkit version: a second run of the same
    code pays nothing.

    The library is built in a private folder and renamed into :func:`library_cache_dir` (an
    interrupted build leaves nothing half-written there). A cache that cannot be written (a
    read-only home) only costs the build.

    Raises
    ------
    ToolchainError
        No C compiler found, or the code does not compile.
    """
    cc = list(compiler) if compiler else find_compiler()
    if cc is None:
        raise ToolchainError(
            "no C compiler found (set $CC or install cc, gcc or clang) to compile generated C"
        )
    target = library_cache_path(files, name, cc, flags, libs)
    if target.is_file():
        try:
            return ctypes.CDLL(str(target))
        except OSError:
            pass  # a damaged file: built again below
    with tempfile.TemporaryDirectory(prefix="fuzzkit-lib-") as tmp:
        library = build_library(Path(tmp), files, name, compiler=cc, flags=flags, libs=libs)
        try:
            target.parent.mkdir(parents=True, exist_ok=True)
            staged = target.with_suffix(f".{os.getpid()}.tmp")
            shutil.copyfile(Path(tmp) / f"lib{name}.so", staged)
            os.replace(staged, target)
        except OSError:
            pass
    return library


class CompiledTable:
    """Generated C compiled into a shared library and loaded; use as a context manager.

    ``eval_batch(points)`` evaluates an ``(n, n_inputs)`` array in one call;
    ``fpi_run(gains, setpoints, measured)`` runs the fuzzy-PI over a sequence.
    """

    def __init__(
        self,
        files: Mapping[str, str],
        name: str,
        number_type: str,
        n_inputs: int,
        n_outputs: int,
        *,
        fpi: bool,
        compiler: Sequence[str] | None = None,
        flags: Sequence[str] = (*STRICT_FLAGS, "-O2"),
        libs: Sequence[str] = ("-lm",),
    ) -> None:
        self.number_type = number_type
        self.n_inputs = n_inputs
        self.n_outputs = n_outputs
        self._tmp = tempfile.TemporaryDirectory(prefix="fuzzkit-cc-")
        harness = {"fuzzkit_harness.c": harness_source(name, number_type, n_inputs, n_outputs, fpi)}
        self.library = build_library(
            Path(self._tmp.name), {**files, **harness}, name,
            compiler=compiler, flags=flags, libs=libs,
        )  # fmt: skip
        ptr = ctypes.POINTER(_CTYPES[number_type])
        self._batch = self.library.fuzzkit_batch_eval
        self._batch.argtypes = [ptr, ptr, ctypes.c_long]
        self._batch.restype = None
        self._fpi: Any = None
        if fpi:
            self._fpi = self.library.fuzzkit_fpi_run
            gptr = ctypes.POINTER(ctypes.c_int32) if number_type == "q15" else ptr
            self._fpi.argtypes = [
                gptr,
                ptr,
                ptr,
                ptr,
                ctypes.c_long,
                ctypes.POINTER(ctypes.c_ulong),
            ]
            self._fpi.restype = None

    def __enter__(self) -> CompiledTable:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    def close(self) -> None:
        """Remove the temporary build folder (the library stays mapped until exit)."""
        self._tmp.cleanup()

    def eval_batch(self, points: npt.ArrayLike) -> npt.NDArray[Any]:
        """``NAME_eval`` on every row of ``points``: returns ``(n, n_outputs)``."""
        dtype = _NUMPY[self.number_type]
        arr = np.ascontiguousarray(np.asarray(points), dtype=dtype)
        if arr.ndim != 2 or arr.shape[1] != self.n_inputs:
            raise ValueError(f"points must have shape (n, {self.n_inputs}), got {arr.shape}")
        out = np.empty((arr.shape[0], self.n_outputs), dtype=dtype)
        ptr = ctypes.POINTER(_CTYPES[self.number_type])
        self._batch(arr.ctypes.data_as(ptr), out.ctypes.data_as(ptr), arr.shape[0])
        return out

    def fpi_run(
        self, gains: Sequence[float], setpoints: npt.ArrayLike, measured: npt.ArrayLike
    ) -> tuple[npt.NDArray[Any], npt.NDArray[np.uint64]]:
        """Run ``NAME_fpi_step`` over the sequences: returns ``(u, faults after each step)``.

        ``gains`` are kp, ki, kx, u_min, u_max; for Q15 their codes
        (``lookup_table.q15_fpi_codes``).
        """
        if self._fpi is None:
            raise ToolchainError("this library was built without the fuzzy-PI API")
        dtype = _NUMPY[self.number_type]
        sp = np.ascontiguousarray(setpoints, dtype=dtype)
        me = np.ascontiguousarray(measured, dtype=dtype)
        q15 = self.number_type == "q15"
        g = np.ascontiguousarray(gains, dtype=np.int32 if q15 else dtype)
        gptr = ctypes.POINTER(ctypes.c_int32) if q15 else ctypes.POINTER(_CTYPES[self.number_type])
        u = np.empty_like(sp)
        faults = np.zeros(sp.shape, dtype=np.uint64)
        ptr = ctypes.POINTER(_CTYPES[self.number_type])
        self._fpi(
            g.ctypes.data_as(gptr),
            sp.ctypes.data_as(ptr),
            me.ctypes.data_as(ptr),
            u.ctypes.data_as(ptr),
            sp.shape[0],
            faults.ctypes.data_as(ctypes.POINTER(ctypes.c_ulong)),
        )
        return u, faults
