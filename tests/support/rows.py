"""Reading a store's tables directly, as a test checks what a refusal left behind."""

from __future__ import annotations

import pytest
from sqlalchemy import create_engine, text

from tests.support.cli_runner import run_cli


def count_rows(url: str, table: str) -> int:
    """Rows of ``table`` in the store at ``url`` (SQLite or PostgreSQL)."""
    engine = create_engine(url.replace("postgresql://", "postgresql+psycopg://", 1))
    try:
        with engine.connect() as connection:
            return int(connection.execute(text(f"SELECT count(*) FROM {table}")).scalar_one())
    finally:
        engine.dispose()


def stored_names(capsys: pytest.CaptureFixture[str], store_url: str) -> list[str]:
    listing = run_cli(capsys, store_url, "datasets", "--json").json()
    return [d["name"] for d in listing["datasets"]]
