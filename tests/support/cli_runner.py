"""Running the CLI in-process and reading what it printed."""

from __future__ import annotations

import json
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
