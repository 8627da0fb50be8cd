"""Atomic output: all files or none, permissions like open(), clear errors naming the path."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest

from fuzzkit.errors import ConfigError
from fuzzkit.fileio import atomic_output, staged_folder, write_atomic, write_tree_atomic


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


def test_staged_folder_appears_whole_on_success(tmp_path: Path) -> None:
    out = tmp_path / "report"
    with staged_folder(out, last="report.md") as stage:
        assert not out.exists() and stage.parent == tmp_path
        (stage / "sub").mkdir()
        (stage / "sub" / "a.txt").write_text("a")
        (stage / "report.md").write_text("r")
    assert sorted(str(p.relative_to(out)) for p in out.rglob("*")) == [
        "report.md",
        "sub",
        "sub/a.txt",
    ]
    assert list(tmp_path.iterdir()) == [out]
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(out.stat().st_mode) == 0o777 & ~umask  # as mkdir would make it


@pytest.mark.parametrize("error", [KeyboardInterrupt, RuntimeError])
def test_staged_folder_interrupted_leaves_nothing_new(
    tmp_path: Path, error: type[BaseException]
) -> None:
    with pytest.raises(error), staged_folder(tmp_path / "new") as stage:
        (stage / "half.png").write_bytes(b"\x89PNG")
        raise error
    assert list(tmp_path.iterdir()) == []

    old = tmp_path / "old"
    (old / "rrd").mkdir(parents=True)
    (old / "report.md").write_text("previous")
    (old / "rrd" / "run.rrd").write_text("previous run")
    with pytest.raises(error), staged_folder(old) as stage:
        (stage / "rrd").mkdir()
        (stage / "report.md").write_text("new")
        raise error
    assert list(tmp_path.iterdir()) == [old]
    assert (old / "report.md").read_text() == "previous"
    assert (old / "rrd" / "run.rrd").read_text() == "previous run"


def test_staged_folder_into_an_existing_folder_replaces_what_it_wrote(tmp_path: Path) -> None:
    out = tmp_path / "out"
    (out / "rrd").mkdir(parents=True)
    (out / "rrd" / "stale.rrd").write_text("stale")
    (out / "report.md").write_text("old")
    (out / "notes.txt").write_text("the user's own file")
    with staged_folder(out, last="report.md") as stage:
        (stage / "rrd").mkdir()
        (stage / "rrd" / "fresh.rrd").write_text("fresh")
        (stage / "report.md").write_text("new")
    assert sorted(str(p.relative_to(out)) for p in out.rglob("*")) == [
        "notes.txt",
        "report.md",
        "rrd",
        "rrd/fresh.rrd",
    ]
    assert (out / "report.md").read_text() == "new"
    assert list(tmp_path.iterdir()) == [out]


def test_staged_folder_refuses_a_file_or_a_missing_parent(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(ConfigError, match="exists and is not a folder"), staged_folder(blocker):
        pass
    with pytest.raises(ConfigError, match="does not exist"), staged_folder(tmp_path / "a" / "b"):
        pass
