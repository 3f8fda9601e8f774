"""The README's walk-through works when pasted into a fresh shell, as written."""

from __future__ import annotations

import os
import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"


def walkthrough() -> str:
    """The bash block that follows the README's ``<!-- walkthrough -->`` marker."""
    text = README.read_text(encoding="utf-8")
    found = re.search(r"<!-- walkthrough -->\s*```bash\n(.*?)```", text, re.S)
    assert found, "the README has no walk-through block"
    return found.group(1)


def test_the_walkthrough_block_is_what_a_user_pastes() -> None:
    lines = [line for line in walkthrough().splitlines() if line.strip()]
    assert lines[0].startswith("source .venv/bin/activate")
    assert all(line.startswith(("source ", "cd ", "touchbench ")) for line in lines)


@pytest.mark.slow
def test_the_readme_walkthrough_runs_as_written(tmp_path: Path) -> None:
    venv = ROOT / ".venv" / "bin" / "activate"
    if not venv.exists():
        pytest.skip(f"the walk-through needs the venv of scripts/install.sh ({venv})")
    script = tmp_path / "walkthrough.sh"
    # what a user does: a fresh shell at the repository root, the lines in order, stopping
    # at the first that fails; TMPDIR keeps the scratch folder inside the test's
    script.write_text("set -euo pipefail\n" + walkthrough(), encoding="utf-8")
    environment = {
        key: value
        for key, value in os.environ.items()
        if not key.startswith(("TOUCHBENCH_", "VIRTUAL_ENV", "PYTHON"))
    }
    environment["TMPDIR"] = str(tmp_path)
    environment["PATH"] = os.pathsep.join(
        p for p in environment.get("PATH", "").split(os.pathsep) if ".venv" not in p
    )
    done = subprocess.run(
        ["bash", "--noprofile", "--norc", "-x", str(script)],
        cwd=ROOT,
        env=environment,
        capture_output=True,
        text=True,
        timeout=1800,
    )
    assert done.returncode == 0, done.stderr[-4000:]
    scratch = next(p for p in tmp_path.iterdir() if p.is_dir())
    for made in ("robot.arff", "confusion.svg", "report.html", "predictions.json"):
        assert (scratch / made).stat().st_size > 100, made
    assert "touchbench.db" in {p.name for p in scratch.iterdir()}
