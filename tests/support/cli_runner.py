"""Running the CLI in-process and reading what it printed."""

from __future__ import annotations

import io
import json
import re
from contextlib import redirect_stderr, redirect_stdout
from dataclasses import dataclass
from typing import Any

import pytest

from touchbench.app.cli.main import main


@dataclass
class CliResult:
    code: int
    out: str
    err: str

    def json(self) -> Any:
        return json.loads(self.out)


def run_cli(capsys: pytest.CaptureFixture[str], db: str, *args: str) -> CliResult:
    """``touchbench --db DB ARGS...`` in this process."""
    capsys.readouterr()
    code = main(["--db", db, *args])
    out, err = capsys.readouterr()
    return CliResult(code, out, err)


def run_cli_captured(db: str, *args: str) -> CliResult:
    """``touchbench --db DB ARGS...`` in this process, its output caught here: for a fixture
    wider than a test, which has no ``capsys``."""
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        code = main(["--db", db, *args])
    return CliResult(code, out.getvalue(), err.getvalue())


#: A command-line word: an option (``--budget``) or a command (``touchbench bench``).
CLI_WORDS = re.compile(r"(^|[\s\"'`(])--[a-z]|touchbench [a-z]")


def one_error_line(result: CliResult, *expected: str) -> str:
    """The single error line of a refused command (exit 2, no traceback)."""
    assert result.code == 2, (result.code, result.out, result.err)
    lines = result.err.strip().splitlines()
    assert len(lines) == 1, result.err
    assert lines[0].startswith("touchbench: error: ")
    for text in expected:
        assert text in lines[0], lines[0]
    return lines[0]
