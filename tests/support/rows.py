"""Reading a store's tables directly, as a test checks what a refusal left behind."""

from __future__ import annotations

import subprocess
import time

import pytest
from sqlalchemy import Engine, create_engine, text

from tests.support.cli_runner import run_cli


def count_rows(url: str, table: str) -> int:
    """Rows of ``table`` in the store at ``url`` (SQLite or PostgreSQL)."""
    engine = _engine(url)
    try:
        with engine.connect() as connection:
            return int(connection.execute(text(f"SELECT count(*) FROM {table}")).scalar_one())
    finally:
        engine.dispose()


def stored_names(capsys: pytest.CaptureFixture[str], store_url: str) -> list[str]:
    listing = run_cli(capsys, store_url, "datasets", "--json").json()
    return [d["name"] for d in listing["datasets"]]


def count_of(url: str, sql: str) -> int:
    """The count a ``SELECT count(*) ...`` finds in the store at ``url``; 0 while its
    tables do not exist yet (a run's process still creating them)."""
    engine = _engine(url)
    try:
        return _count(engine, sql)
    finally:
        engine.dispose()


def wait_for_count(
    url: str, sql: str, at_least: int, child: subprocess.Popen[bytes], deadline: float
) -> None:
    """Wait until :func:`count_of` ``sql`` reaches ``at_least`` while ``child`` (the process
    writing the rows) lives, until ``deadline`` (``time.monotonic()``) at most."""
    engine = _engine(url)  # one connection for every poll, not one (a PostgreSQL backend) each
    try:
        while _count(engine, sql) < at_least:
            assert child.poll() is None, child.stderr.read().decode() if child.stderr else ""
            assert time.monotonic() < deadline, f"fewer than {at_least} rows by the deadline: {sql}"
            time.sleep(0.05)
    finally:
        engine.dispose()


def _engine(url: str) -> Engine:
    return create_engine(url.replace("postgresql://", "postgresql+psycopg://", 1))


def _count(engine: Engine, sql: str) -> int:
    try:
        with engine.connect() as connection:
            return int(connection.execute(text(sql)).scalar() or 0)
    except Exception:
        return 0
