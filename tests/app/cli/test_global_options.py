"""`--db` after the command's name, and progress on stderr when output is redirected."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from tests.support.synthetic import touch_arff
from touchbench.app.cli.main import global_options_first, main

ROOT = Path(__file__).resolve().parents[3]


def test_db_after_the_command_is_the_store(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    url = f"sqlite:///{tmp_path / 'after.db'}"
    data = touch_arff(tmp_path / "touch.arff", n=30)
    assert main(["import", str(data), "--db", url, "--name", "touch"]) == 0
    capsys.readouterr()
    assert main(["datasets", "--json", f"--db={url}"]) == 0
    assert '"name": "touch"' in capsys.readouterr().out
    assert main(["--db", url, "datasets", "--json"]) == 0
    assert '"name": "touch"' in capsys.readouterr().out


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["datasets", "--db", "U", "--json"], ["--db", "U", "datasets", "--json"]),
        (["--db", "U", "datasets"], ["--db", "U", "datasets"]),
        (["show", "x", "--", "--db", "U"], ["show", "x", "--", "--db", "U"]),
        (["--version"], ["--version"]),
    ],
)
def test_global_options_are_moved_before_the_command(args: list[str], expected: list[str]) -> None:
    assert global_options_first(args) == expected


def test_bench_with_json_redirected_shows_progress_lines_on_stderr(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'progress.db'}"
    data = touch_arff(tmp_path / "touch.arff", n=60)
    command = [sys.executable, "-m", "touchbench.app.cli.main"]
    imported = subprocess.run(
        [*command, "import", str(data), "--db", url], capture_output=True, text=True, cwd=ROOT
    )
    assert imported.returncode == 0, imported.stderr
    done = subprocess.run(
        [
            *command,
            *("--db", url, "bench", "touch", "--target", "gesture"),
            *("--classifiers", "zeror,nb", "--folds", "3", "--json"),
        ],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.lstrip().startswith("{")  # stdout stays the JSON
    lines = [line for line in done.stderr.splitlines() if line.startswith("progress: ")]
    assert lines[0] == "progress: 6 task(s), 0 done before"
    assert len(lines) == 7 and lines[-1].startswith("progress: 6/6 ")
    assert all(line.endswith(": ok") for line in lines[1:])
