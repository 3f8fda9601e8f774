"""A store's URL is shown with its password hidden wherever touchbench prints it: in the
messages of a store it cannot open or use, on the CLI and in ``touchbench serve``."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.support.cli_runner import run_cli
from touchbench.app.errors import AppError
from touchbench.app.store.database import Store, display_url

ROOT = Path(__file__).resolve().parents[3]
PASSWORD = "pa55word-of-the-test"


@pytest.mark.parametrize(
    ("url", "shown"),
    [
        ("postgresql://u:secret@h:5432/x", "postgresql://u:***@h:5432/x"),
        ("postgresql+psycopg://u:p%40ss@h/x", "postgresql+psycopg://u:***@h/x"),
        ("postgresql://:secret@h/x", "postgresql://:***@h/x"),
        ("postgresql://u@h/x", "postgresql://u@h/x"),
        ("sqlite:///touchbench.db", "sqlite:///touchbench.db"),
        # Not parsed by SQLAlchemy (a port that is not a number): hidden all the same.
        ("postgresql://u:secret@h:port/x", "postgresql://u:***@h:port/x"),
        # An unescaped @ in the password: its end would pass for the host.
        ("postgresql://u:sec@ret@h/x", "postgresql://u:***@h/x"),
        ("postgresql://u:se/c@ret@h:port/x", "postgresql://u:***@h:port/x"),
    ],
)
def test_display_url_hides_the_password(url: str, shown: str) -> None:
    assert display_url(url) == shown


@pytest.mark.parametrize(
    ("url", "message"),
    [
        (f"postgresql://u:{PASSWORD}@127.0.0.1:1/x", "cannot open the store at"),
        (f"postgresql://u:{PASSWORD}@127.0.0.1:port/x", "not a database URL"),
        (f"mysql://u:{PASSWORD}@127.0.0.1/x", "cannot use the database URL"),
        (f"nosuch://u:{PASSWORD}@127.0.0.1/x", "cannot use the database URL"),
    ],
)
def test_a_store_that_cannot_be_opened_is_one_line_without_its_password(
    capsys: pytest.CaptureFixture[str], url: str, message: str
) -> None:
    with pytest.raises(AppError, match=message) as raised:
        Store(url)
    assert PASSWORD not in str(raised.value) and "u:***@127.0.0.1" in str(raised.value)
    result = run_cli(capsys, url, "datasets")
    assert result.code == 2
    [line] = result.err.splitlines()
    assert line.startswith("touchbench: error: ") and message in line
    assert PASSWORD not in result.err + result.out


def test_serve_on_a_store_it_cannot_reach_says_so_without_the_password(tmp_path: Path) -> None:
    environment = {
        **os.environ,
        "TOUCHBENCH_DATABASE_URL": f"postgresql://u:{PASSWORD}@127.0.0.1:1/x",
        "TOUCHBENCH_WORK_DIR": str(tmp_path / "work"),
    }
    done = subprocess.run(
        [sys.executable, "-m", "touchbench.app.cli.main", "serve", "--port", "1"],
        cwd=ROOT,
        env=environment,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 2
    [line] = done.stderr.splitlines()
    assert line.startswith("touchbench: error: cannot open the store at ")
    assert "u:***@127.0.0.1:1/x" in line and PASSWORD not in done.stderr + done.stdout
