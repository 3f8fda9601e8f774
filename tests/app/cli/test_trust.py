"""Issue 21, the command line's side of items 4, 8, 9 and 11: one line and exit 2 (or a
quiet exit where nothing went wrong), nothing half-written in the store (SQLite and
PostgreSQL); the process-level cases (a busy port, a closed pipe, a read-only store, an
early Ctrl-C) in a subprocess."""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.support.cli_runner import one_error_line, run_cli
from tests.support.rows import stored_names
from tests.support.service import ROOT, free_port
from tests.support.synthetic import touch_arff


def _command(database: str, *args: str) -> list[str]:
    return [sys.executable, "-m", "touchbench.app.cli.main", "--db", database, *args]


def _environment() -> dict[str, str]:
    environment = {**os.environ, "PYTHONPATH": str(ROOT)}
    environment.pop("TOUCHBENCH_DEBUG", None)
    return environment


def test_import_refuses_a_csv_field_over_the_limit(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    path = tmp_path / "long.csv"
    path.write_text("a,b,cls\n1,2,u\n" + "x" * 131_073 + ",3,v\n", encoding="utf-8")
    result = run_cli(capsys, store_url, "import", str(path))
    one_error_line(result, f"{path}:3: a field is longer than 131,072 characters")
    assert stored_names(capsys, store_url) == []


def test_import_refuses_meka_targets_that_are_not_a_number(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    path = tmp_path / "meka.arff"
    path.write_text(
        "@relation 'r: -C abc'\n@attribute a numeric\n@attribute cls {u,v}\n@data\n1,u\n",
        encoding="utf-8",
    )
    one_error_line(run_cli(capsys, store_url, "import", str(path)), f"{path}:1:", "'abc'")
    assert stored_names(capsys, store_url) == []


@pytest.mark.parametrize("name", ["a/b", "../../etc/passwd", "bell\x07", " lead"])
def test_every_command_that_takes_a_name_refuses_one_that_cannot_be_reached(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path, name: str
) -> None:
    data = touch_arff(tmp_path / "touch.arff", n=30)
    one_error_line(
        run_cli(capsys, store_url, "import", str(data), "--name", name), "--name: a dataset name"
    )
    assert run_cli(capsys, store_url, "import", str(data)).code == 0
    one_error_line(run_cli(capsys, store_url, "rename", "touch", name), "NEW: a dataset name")
    trained = run_cli(
        capsys, store_url, "train", "touch", "--classifier", "nb", "--target", "gesture",
        "--name", name,
    )  # fmt: skip
    one_error_line(trained, "--name: a model name")
    assert stored_names(capsys, store_url) == ["touch"]
    assert run_cli(capsys, store_url, "models", "--json").json()["models"] == []


def test_a_closed_pipe_ends_any_command_quietly(tmp_path: Path) -> None:
    database = f"sqlite:///{tmp_path / 'touchbench.db'}"
    wide = tmp_path / "wide.arff"
    lines = ["@relation wide", *(f"@attribute a{i} numeric" for i in range(400)), "@data"]
    wide.write_text("\n".join([*lines, ",".join(["1"] * 400)]) + "\n", encoding="utf-8")
    assert (
        subprocess.run(_command(database, "import", str(wide)), env=_environment()).returncode == 0
    )
    for args in (("show", "wide"), ("show", "wide", "--json"), ("export", "wide"), ("--help",)):
        reader = subprocess.Popen(
            ["head", "-c", "1"], stdin=subprocess.PIPE, stdout=subprocess.DEVNULL
        )
        assert reader.stdin is not None
        writer = subprocess.run(
            _command(database, *args), stdout=reader.stdin, stderr=subprocess.PIPE,
            env=_environment(),
        )  # fmt: skip
        reader.stdin.close()
        reader.wait()
        assert (writer.returncode, writer.stderr.decode()) == (0, ""), args


def test_serve_on_a_busy_port_says_so_in_one_line(tmp_path: Path) -> None:
    port = free_port()
    with socket.socket() as holder:
        holder.bind(("127.0.0.1", port))
        holder.listen()
        done = subprocess.run(
            _command(f"sqlite:///{tmp_path / 'touchbench.db'}", "serve", "--port", str(port)),
            capture_output=True,
            env={**_environment(), "TOUCHBENCH_WORK_DIR": str(tmp_path / "work")},
            timeout=120,
        )
    assert done.returncode == 2, done.stderr
    lines = done.stderr.decode().strip().splitlines()
    assert len(lines) == 1, lines
    assert f"cannot listen on 127.0.0.1:{port}" in lines[0]
    assert done.stdout == b""


@pytest.mark.skipif(shutil.which("unshare") is None, reason="needs unshare(1)")
def test_a_read_only_store_answers_in_one_line(tmp_path: Path) -> None:
    """A store file on a read-only mount (as root, file modes do not stop writes)."""
    database = tmp_path / "touchbench.db"
    data = touch_arff(tmp_path / "touch.arff", n=30)
    url = f"sqlite:///{database}"
    assert subprocess.run(_command(url, "import", str(data)), env=_environment()).returncode == 0
    other = touch_arff(tmp_path / "other.arff", n=30, seed=1)
    script = (
        f"mount --bind {database} {database} && mount -o remount,bind,ro {database} && "
        f"exec {' '.join(_command(url, 'import', str(other)))}"
    )
    done = subprocess.run(
        ["unshare", "--mount", "sh", "-c", script], capture_output=True, env=_environment()
    )
    if b"mount:" in done.stderr or b"unshare:" in done.stderr:
        pytest.skip(f"no read-only mount here: {done.stderr.decode().strip()}")
    lines = done.stderr.decode().strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1, done.stderr
    assert "readonly database" in lines[0] and "[SQL" not in lines[0]


#: A compiled module the CLI loads right after ``app.cli`` (typing's), and never Python's own
#: start-up: once mapped into the process, touchbench's code runs, whatever the load.
FIRST_OWN_LIBRARY = "/_typing."


def _wait_for_library(process: subprocess.Popen[bytes], name: str) -> bool:
    """Whether ``process`` maps a library whose path holds ``name`` before it ends."""
    maps = Path(f"/proc/{process.pid}/maps")
    while process.poll() is None:
        try:
            if name in maps.read_text():
                return True
        except OSError:  # the process ended meanwhile
            return False
        time.sleep(0.002)
    return False


@pytest.mark.skipif(not Path("/proc/self/maps").exists(), reason="needs /proc")
@pytest.mark.parametrize("delay", [0.0, 0.05, 0.2, 0.4, 0.6])
def test_an_early_ctrl_c_of_import_prints_no_traceback(tmp_path: Path, delay: float) -> None:
    """Ctrl-C while the CLI is still loading its modules, or already importing (counted
    from when touchbench's own code runs: before, Python itself is starting up)."""
    data = touch_arff(tmp_path / "touch.arff", n=3000)
    process = subprocess.Popen(
        _command(f"sqlite:///{tmp_path / 'touchbench.db'}", "import", str(data)),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        env=_environment(),
    )
    if not _wait_for_library(process, FIRST_OWN_LIBRARY):
        process.communicate(timeout=120)
        pytest.skip(f"the CLI never mapped {FIRST_OWN_LIBRARY} (another Python build?)")
    time.sleep(delay)  # not a check of time: where in its start the interrupt lands
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=120)
    assert b"Traceback" not in err, err.decode()
    if process.returncode != 0:  # the import may have finished before the signal
        assert process.returncode in (130, -signal.SIGINT), process.returncode
        assert err.decode().strip() == "touchbench: interrupted"


FINALISER_INTERRUPTED = """
import signal, sys, time
import touchbench.app.cli
from touchbench.app.cli.signals import Interrupted, interrupts

class Finalised:
    def __del__(self):
        signal.raise_signal(signal.SIGINT)
        for _ in range(10_000):  # the handler runs here, inside the finaliser
            pass

with interrupts():
    try:
        Finalised()
        time.sleep(5)  # the command goes on; the interrupt comes back within it
    except Interrupted as interrupt:
        print("interrupted after the finaliser:", interrupt)
        sys.exit(0)
print("the interrupt was lost")
sys.exit(1)
"""


def test_a_ctrl_c_inside_a_finaliser_is_not_lost() -> None:
    """Python cannot raise from a finaliser (a weakref callback of SQLAlchemy's, in the CI
    run that found this): the interrupt comes again, in ordinary code, without a traceback."""
    done = subprocess.run(
        [sys.executable, "-c", FINALISER_INTERRUPTED],
        capture_output=True,
        env=_environment(),
        timeout=60,
    )
    assert done.stderr == b"", done.stderr.decode()
    assert done.stdout.decode().strip() == "interrupted after the finaliser: SIGINT"
    assert done.returncode == 0
