"""Atomic output: all files or none, permissions like open(), clear errors naming the path."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest

from fuzzkit.errors import ConfigError
from fuzzkit.fileio import atomic_output, write_atomic, write_tree_atomic


def test_tree_is_written_with_subfolders_and_umask_permissions(tmp_path: Path) -> None:
    out = tmp_path / "gen"
    written = write_tree_atomic(out, {"a.h": "A", "sub/b.c": b"B"})
    assert sorted(p.relative_to(out).as_posix() for p in written) == ["a.h", "sub/b.c"]
    assert (out / "a.h").read_text() == "A" and (out / "sub/b.c").read_bytes() == b"B"
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE((out / "a.h").stat().st_mode) == 0o666 & ~umask


def test_a_folder_in_the_way_leaves_everything_as_it_was(tmp_path: Path) -> None:
    out = tmp_path / "hw"
    (out / "x.c").mkdir(parents=True)
    (out / "x.h").write_text("old")
    with pytest.raises(ConfigError, match=r"x\.c: is a directory"):
        write_tree_atomic(out, {"x.h": "new", "x.c": "new"})
    assert (out / "x.h").read_text() == "old"  # not half-published
    assert sorted(p.name for p in out.iterdir()) == ["x.c", "x.h"]  # no temporaries left


def test_a_file_where_a_folder_must_go_is_a_clear_error(tmp_path: Path) -> None:
    (tmp_path / "afile").write_text("x")
    with pytest.raises(ConfigError, match=r"afile: exists and is not a directory"):
        write_tree_atomic(tmp_path / "afile" / "sub", {"x.h": "new"})
    with pytest.raises(ConfigError, match=r"afile: exists and is not a directory"):
        write_tree_atomic(tmp_path / "afile", {"x.h": "new"})


def test_paths_may_not_escape_the_folder(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="must be relative"):
        write_tree_atomic(tmp_path, {"../evil.h": "x"})
    assert list(tmp_path.iterdir()) == []


def test_failure_while_writing_removes_created_folders(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import errno
    import tempfile

    real = tempfile.mkstemp
    calls = []

    def full_disk(*args: object, **kwargs: object) -> tuple[int, str]:
        calls.append(1)
        if len(calls) == 2:
            raise OSError(errno.ENOSPC, "No space left on device", str(kwargs.get("dir")))
        return real(*args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr("fuzzkit.fileio.tempfile.mkstemp", full_disk)
    out = tmp_path / "new" / "deeper"
    with pytest.raises(ConfigError, match="No space left on device"):
        write_tree_atomic(out, {"ok.h": "fine", "sub/second.c": "never"})
    assert list(tmp_path.iterdir()) == []  # neither files, temporaries nor new folders remain


def test_single_file_and_context_manager(tmp_path: Path) -> None:
    target = tmp_path / "r.rrd"
    with pytest.raises(ValueError), atomic_output(target) as tmp:
        Path(tmp).write_text("partial")
        raise ValueError("failed half-way")
    assert list(tmp_path.iterdir()) == []
    write_atomic(target, "whole")
    assert target.read_text() == "whole"
    with pytest.raises(ConfigError, match="is a directory"):
        write_atomic(tmp_path, "x")
    with pytest.raises(ConfigError, match="does not exist"):
        write_atomic(tmp_path / "missing" / "x.txt", "x")
