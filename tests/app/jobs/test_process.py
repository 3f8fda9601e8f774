"""``python -m app.jobs.process``: the store's URL from the environment (as the dispatcher
gives it) or ``--db`` (by hand), and a store it cannot reach said in one line without the
URL's password."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from touchbench.app.jobs.process import DATABASE_URL_VARIABLE

ROOT = Path(__file__).resolve().parents[3]
#: Nothing listens on port 1: the connection is refused at once.
UNREACHABLE = "postgresql://someone:pa55word-of-the-test@127.0.0.1:1/touchbench"


def _process(*arguments: str, url: str | None) -> subprocess.CompletedProcess[str]:
    environment = {k: v for k, v in os.environ.items() if k != DATABASE_URL_VARIABLE}
    if url is not None:
        environment[DATABASE_URL_VARIABLE] = url
    return subprocess.run(
        [sys.executable, "-m", "touchbench.app.jobs.process", *arguments],
        cwd=ROOT,
        env=environment,
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_the_store_url_comes_from_the_environment() -> None:
    done = _process("run", "5", url=UNREACHABLE)
    assert done.returncode == 1
    assert done.stdout == ""
    [line] = done.stderr.splitlines()
    assert line.startswith("run 5: cannot open the store at postgresql+psycopg://someone:***@")
    assert "pa55word" not in done.stderr


def test_db_is_still_taken_by_hand() -> None:
    done = _process("--db", UNREACHABLE, "job", "7", url=None)
    assert done.returncode == 1
    [line] = done.stderr.splitlines()
    assert line.startswith("job 7: cannot open the store at ")
    assert "pa55word" not in done.stderr


def test_no_store_at_all_is_a_usage_error() -> None:
    done = _process("run", "5", url=None)
    assert done.returncode == 2
    assert f"no store: set {DATABASE_URL_VARIABLE} or pass --db" in done.stderr
