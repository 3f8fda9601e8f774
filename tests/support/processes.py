"""A `touchbench bench` in a process of its own, and reading its store meanwhile; a Python
script in a fresh interpreter."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

from sqlalchemy import create_engine, text

from tests.support.gate import Gate
from tests.support.service import ROOT


def bench_process(
    url: str, gate: Gate, *args: str, ignore_sigint: bool = False
) -> subprocess.Popen[bytes]:
    """``touchbench bench`` in a subprocess that knows the ``gate`` entry; with
    ``ignore_sigint`` it starts as a background job of a script does, SIGINT ignored."""
    command = [sys.executable, "-m", "touchbench.app.cli.main", "--db", url, "bench", *args]

    def ignore() -> None:
        signal.signal(signal.SIGINT, signal.SIG_IGN)

    return subprocess.Popen(
        command,
        cwd=ROOT,
        env={**os.environ, **gate.environment()},
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        preexec_fn=ignore if ignore_sigint else None,
    )


def store_engine(url: str) -> Any:
    return create_engine(url.replace("postgresql://", "postgresql+psycopg://", 1))


def scalar(url: str, query: str) -> Any:
    engine = store_engine(url)
    try:
        with engine.connect() as connection:
            return connection.execute(text(query)).scalar()
    finally:
        engine.dispose()


def wait_for_results(url: str, child: subprocess.Popen[bytes], at_least: int) -> None:
    deadline = time.monotonic() + 120
    engine = store_engine(url)  # one connection for every poll, not one (a backend) each
    try:
        while True:
            with engine.connect() as connection:
                found = connection.execute(text("SELECT count(*) FROM fold_results")).scalar()
            if (found or 0) >= at_least:
                return
            assert child.poll() is None, child.stderr.read().decode() if child.stderr else ""
            assert time.monotonic() < deadline, "the run recorded nothing in two minutes"
            time.sleep(0.05)
    finally:
        engine.dispose()


def run_script(script: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    """``script`` run by a fresh interpreter in ``cwd`` with this checkout importable; the
    test fails with its stderr if it does not exit 0."""
    done = subprocess.run(
        [sys.executable, "-c", script],
        capture_output=True,
        text=True,
        cwd=cwd,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        timeout=300,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    return done
