"""Atomic file output: a reader never sees a half-written file, and a failure leaves none."""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path

from fuzzkit.errors import ConfigError


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _publish(tmp: str, target: Path) -> None:
    # mkstemp creates owner-only files; give the result the permissions a plain open() would
    os.chmod(tmp, 0o666 & ~_umask())
    os.replace(tmp, target)


def check_output_path(path: str | os.PathLike[str], what: str = "file") -> Path:
    """``path`` as a Path if a file can be created there; else a ConfigError saying why.

    Commands that write several files call this for all of them first, so that a bad second
    path does not leave the first file written.
    """
    target = Path(path)
    parent = target.parent if str(target.parent) else Path(".")
    if target.is_dir():
        raise ConfigError(f"{target}: is a directory (expected a {what} path)")
    if not parent.is_dir():
        raise ConfigError(f"{target}: folder {parent} does not exist")
    return target


@contextmanager
def atomic_output(path: str | os.PathLike[str], what: str = "file") -> Iterator[str]:
    """Yield a temporary path beside ``path``; on success it becomes ``path``, else vanishes.

    For writers that need a file name rather than bytes (a Rerun recording, a figure).

    Raises
    ------
    ConfigError
        If the parent folder is missing or ``path`` is an existing folder.
    """
    target = check_output_path(path, what)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    except OSError as exc:
        raise ConfigError(f"{target}: cannot write here ({exc.strerror})") from exc
    os.close(fd)
    try:
        yield tmp
        _publish(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_atomic(path: str | os.PathLike[str], data: str | bytes) -> Path:
    """Write ``data`` to ``path`` through a temporary file in the same folder, then rename.

    Raises
    ------
    ConfigError
        If the parent folder is missing or ``path`` is an existing folder.
    """
    payload = data.encode("utf-8") if isinstance(data, str) else data
    with atomic_output(path) as tmp, open(tmp, "wb") as fh:
        fh.write(payload)
    return Path(path)


def write_tree_atomic(
    folder: str | os.PathLike[str], files: Mapping[str, str | bytes]
) -> list[Path]:
    """Write ``{relative path: content}`` under ``folder``: all files or none.

    Every target is checked first (not a folder, no file where a folder must go), every file
    is then written to a temporary sibling, and only when all are written are they renamed
    into place; on any error the temporaries and the folders this call created are removed,
    so the output folder is left as it was.

    Raises
    ------
    ConfigError
        A path escapes ``folder``, a target is a folder, or a file stands where a folder
        must be created; or the file system refuses a write (the message names the path).
    """
    root = Path(folder)
    targets: dict[Path, bytes] = {}
    for rel, data in files.items():
        rp = Path(rel)
        if rp.is_absolute() or ".." in rp.parts:
            raise ConfigError(f"{rel}: output paths must be relative and stay inside {root}")
        targets[root / rp] = data.encode("utf-8") if isinstance(data, str) else data
    for target in targets:
        if target.is_dir():
            raise ConfigError(f"{target}: is a directory (expected a file to write)")
        for parent in [*reversed(target.parents[: len(target.relative_to(root).parts) - 1]), root]:
            if parent.exists() and not parent.is_dir():
                raise ConfigError(f"{parent}: exists and is not a directory (expected a folder)")
        anc = root
        while not anc.exists() and anc != anc.parent:
            anc = anc.parent
        if not anc.is_dir():
            raise ConfigError(f"{anc}: exists and is not a directory (expected a folder)")
    created: list[Path] = []
    staged: list[tuple[str, Path]] = []
    try:
        for target, payload in targets.items():
            for d in [*reversed(target.parent.parents), target.parent]:
                if not d.exists():
                    d.mkdir()
                    created.append(d)
            fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
            with os.fdopen(fd, "wb") as fh:
                fh.write(payload)
            staged.append((tmp, target))
        for tmp, target in staged:
            _publish(tmp, target)
    except BaseException as exc:
        for tmp, _ in staged:
            Path(tmp).unlink(missing_ok=True)
        for d in reversed(created):
            with contextlib.suppress(OSError):
                d.rmdir()
        if isinstance(exc, OSError):
            where = exc.filename or root
            raise ConfigError(f"{where}: cannot write ({exc.strerror})") from exc
        raise
    return list(targets)


@contextmanager
def staged_folder(
    folder: str | os.PathLike[str], last: str | None = None, what: str = "folder"
) -> Iterator[Path]:
    """Yield an empty staging folder beside ``folder``; on success its entries move into
    ``folder``, on any error or Ctrl-C it is removed and ``folder`` is left as it was.

    For commands that write many files (a report): a reader finds the old output or the
    complete new one, never a mix. A new ``folder`` appears in one rename; into an existing
    one each entry is renamed into place (a sub-folder of the same name is replaced whole),
    ``last`` (say ``report.md``) after all others, so its presence marks a complete output.

    Raises
    ------
    ConfigError
        ``folder`` is a file, its parent is missing, or nothing can be created there.
    """
    target = Path(folder)
    parent = target.parent if str(target.parent) else Path(".")
    if target.exists() and not target.is_dir():
        raise ConfigError(f"{target}: exists and is not a folder (expected the {what})")
    if not parent.is_dir():
        raise ConfigError(f"{target}: folder {parent} does not exist")
    try:
        stage = Path(tempfile.mkdtemp(prefix=f".{target.name}.", suffix=".partial", dir=parent))
    except OSError as exc:
        raise ConfigError(f"{target}: cannot write here ({exc.strerror})") from exc
    try:
        yield stage
        os.chmod(stage, 0o777 & ~_umask())  # mkdtemp makes it owner-only
        if not target.exists():
            os.rename(stage, target)
            return
        entries = sorted(stage.iterdir(), key=lambda p: (p.name == last, p.name))
        for entry in entries:
            dest = target / entry.name
            if entry.is_dir() and dest.is_dir():
                old = stage / f".{entry.name}.old"
                os.rename(dest, old)
                os.rename(entry, dest)
            else:
                os.replace(entry, dest)
    finally:
        shutil.rmtree(stage, ignore_errors=True)
