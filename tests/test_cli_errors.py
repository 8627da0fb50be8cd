"""Which failures the ``fuzzkit`` command reports as the user's error and which as its own bug."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest

import fuzzkit.cli
import fuzzkit.cli.rulebase
from fuzzkit import errors
from fuzzkit.cli import COMMAND_MODULES, EXIT_BAD_INPUT, EXIT_FAILURE, main


def _fuzzkit_errors() -> list[type[errors.FuzzkitError]]:
    found: list[type[errors.FuzzkitError]] = []
    todo = [errors.FuzzkitError]
    while todo:
        cls = todo.pop()
        found.append(cls)
        todo.extend(cls.__subclasses__())
    return sorted(set(found), key=lambda c: c.__name__)


def _raising(exc: Exception) -> object:
    def handler(args: argparse.Namespace) -> int:
        raise exc

    return handler


def _instance(cls: type[errors.FuzzkitError]) -> errors.FuzzkitError:
    # whatever the class's own constructor wants (problems, a format and items, ...)
    exc = cls.__new__(cls)
    Exception.__init__(exc, "bad thing")
    return exc


@pytest.mark.parametrize("cls", _fuzzkit_errors(), ids=lambda c: c.__name__)
def test_every_fuzzkit_error_is_the_users_error(
    cls: type[errors.FuzzkitError],
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.setattr(fuzzkit.cli.rulebase, "cmd_validate", _raising(_instance(cls)))
    assert main(["validate", "macvicar_whelan"]) == EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert err.startswith("fuzzkit: error: ") and "bad thing" in err
    assert "internal error" not in err


def test_an_os_error_is_the_users_error(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    missing = FileNotFoundError(2, "No such file or directory", "gains.yaml")
    monkeypatch.setattr(fuzzkit.cli.rulebase, "cmd_validate", _raising(missing))
    assert main(["validate", "macvicar_whelan"]) == EXIT_BAD_INPUT
    assert capsys.readouterr().err.startswith("fuzzkit: error: [Errno 2]")


@pytest.mark.parametrize(
    "exc",
    [ValueError("math domain error"), TypeError("unsupported operand"), KeyError("kp")],
    ids=lambda e: type(e).__name__,
)
def test_any_other_error_is_an_internal_error(
    exc: Exception, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.delenv("FUZZKIT_DEBUG", raising=False)
    monkeypatch.setattr(fuzzkit.cli.rulebase, "cmd_validate", _raising(exc))
    assert main(["validate", "macvicar_whelan"]) == EXIT_FAILURE
    err = capsys.readouterr().err
    assert err.startswith(f"fuzzkit: internal error: {type(exc).__name__}: ")
    assert "this is a bug in fuzzkit" in err and "Traceback" not in err


def test_an_internal_value_error_is_raised_with_fuzzkit_debug(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setenv("FUZZKIT_DEBUG", "1")
    monkeypatch.setattr(fuzzkit.cli.rulebase, "cmd_validate", _raising(ValueError("deep")))
    with pytest.raises(ValueError, match="deep"):
        main(["validate", "macvicar_whelan"])


@pytest.mark.parametrize(
    ("module", "source"),
    [
        ("no_such_command_module", None),  # the module itself is missing
        ("broken_command_module", "import no_such_dependency_xyz\n"),  # it imports, and fails
        ("raising_command_module", "raise ImportError('cannot import name x from y')\n"),
    ],
)
def test_a_command_module_that_fails_to_import_fails_loudly(
    module: str,
    source: str | None,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    if source is not None:
        (tmp_path / f"{module}.py").write_text(source)
        monkeypatch.setattr(fuzzkit.cli, "__path__", [*fuzzkit.cli.__path__, str(tmp_path)])
    monkeypatch.delenv("FUZZKIT_DEBUG", raising=False)
    monkeypatch.setattr(fuzzkit.cli, "COMMAND_MODULES", (*COMMAND_MODULES, module))
    assert main(["--help"]) == EXIT_FAILURE  # not the help of the other commands
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith(
        f"fuzzkit: internal error: CommandModuleError: command module fuzzkit.cli.{module} "
        "failed to import"
    )
    assert "this is a bug in fuzzkit" in captured.err
