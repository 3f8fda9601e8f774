"""SIGTERM to pytest tears fixtures down (tests/support/termination.py): no server is left."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

OWNER = """
import subprocess, time
import pytest

@pytest.fixture
def child(tmp_path_factory):
    process = subprocess.Popen(["sleep", "300"], start_new_session=True)
    yield process
    process.kill()
    process.wait()

def test_waits(child):
    open("{pid_file}", "w").write(str(child.pid))
    time.sleep(120)
"""


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    with open(f"/proc/{pid}/stat") as stat:  # a zombie is gone for our purpose
        return stat.read().split()[2] != "Z"


def _child_after_sigterm(tmp_path: Path, *plugin: str) -> int:
    pid_file = tmp_path / f"pid{len(plugin)}"
    test = tmp_path / f"test_owner{len(plugin)}.py"
    test.write_text(OWNER.format(pid_file=pid_file))
    pytest_process = subprocess.Popen(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *plugin, str(test)],
        cwd=tmp_path,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    deadline = time.monotonic() + 60
    while not pid_file.exists() or not pid_file.read_text():
        assert time.monotonic() < deadline and pytest_process.poll() is None
        time.sleep(0.1)
    pytest_process.send_signal(signal.SIGTERM)
    pytest_process.wait(timeout=60)
    return int(pid_file.read_text())


def test_sigterm_tears_fixtures_down_only_with_the_plugin(tmp_path: Path) -> None:
    orphan = _child_after_sigterm(tmp_path)
    try:
        assert _alive(orphan), "without the plugin the fixture's process outlives pytest"
    finally:
        os.kill(orphan, signal.SIGKILL)
    cleaned = _child_after_sigterm(tmp_path, "-p", "tests.support.termination")
    time.sleep(0.2)
    assert not _alive(cleaned)
