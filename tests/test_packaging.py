"""touchbench installs as one import name: the wheel, a fresh environment, old stores.

The wheel is built from a copy of the repository's package folders, installed with its
dependencies (the core, no extra) into a new virtual environment outside the repository,
and used there as a researcher would: the console script, ``import``, a store written
before the move.
"""

from __future__ import annotations

import ast
import gzip
import json
import os
import shutil
import subprocess
import sys
import venv
import zipfile
from pathlib import Path

import pytest

from tests.support.predictions import assert_same_predictions

ROOT = Path(__file__).resolve().parents[1]
PARTS = ("app", "benchmark", "features", "drivers")
BEFORE = ROOT / "tests" / "app" / "store" / "data" / "before-one-package"


def _python_files() -> list[Path]:
    folders = [ROOT / part for part in (*PARTS, "touchbench", "tests", "perf", "examples")]
    return [path for folder in folders if not folder.is_symlink() for path in folder.rglob("*.py")]


def test_no_module_imports_a_part_by_its_old_top_level_name() -> None:
    found = []
    for path in _python_files():
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            names = []
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
            found += [
                f"{path.relative_to(ROOT)}:{node.lineno}: {name}"
                for name in names
                if name.split(".")[0] in PARTS
            ]
    assert found == []


def test_the_package_links_each_part_to_its_top_level_folder() -> None:
    for part in PARTS:
        link = ROOT / "touchbench" / part
        assert link.is_symlink() and link.resolve() == ROOT / part, part


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The wheel built from a copy of the repository (the build writes beside its sources)."""
    source = tmp_path_factory.mktemp("source")
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, source / name)
    for folder in (*PARTS, "touchbench"):
        shutil.copytree(
            ROOT / folder,
            source / folder,
            symlinks=True,
            ignore=shutil.ignore_patterns("__pycache__"),
        )
    dist = tmp_path_factory.mktemp("dist")
    build = [sys.executable, "-m", "pip", "wheel", str(source), "--no-deps", "--quiet"]
    built = subprocess.run(
        [*build, "--no-build-isolation", "--wheel-dir", str(dist)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert built.returncode == 0, built.stderr[-3000:]
    (path,) = dist.glob("touchbench-*.whl")
    return path


def test_the_wheel_installs_one_top_level_name(wheel: Path) -> None:
    with zipfile.ZipFile(wheel) as archive:
        tops = {name.split("/", 1)[0] for name in archive.namelist()}
        names = set(archive.namelist())
    assert {top for top in tops if not top.endswith(".dist-info")} == {"touchbench"}
    # the data files that the service and the store read at run time came along
    assert "touchbench/app/store/migrations/env.py" in names
    assert "touchbench/app/web/templates/base.html.j2" in names
    assert "touchbench/py.typed" in names


# pip byte-compiles every file of every dependency (SciPy, pandas, Dask, Matplotlib, ...)
# by default: more than half of the install's CPU (84 s of CPU with it, 37 s without). The
# environment is as fresh without: Python compiles the modules that it imports when it
# imports them.
NO_COMPILE = ("--no-compile",)
# the versions that scripts/install.sh installs and the tests run on (pip then resolves
# pinned versions, most of them already in its cache, instead of the newest of each)
CONSTRAINTS = ROOT / "scripts" / "constraints.txt"


def _fresh_environment(wheel: Path, folder: Path) -> Path:
    """A new virtual environment with the wheel and its core dependencies."""
    venv.EnvBuilder(with_pip=True).create(folder)
    installed = subprocess.run(
        [
            str(folder / "bin" / "python"),
            "-m",
            "pip",
            "install",
            "--quiet",
            *NO_COMPILE,
            "--constraint",
            str(CONSTRAINTS),
            str(wheel),
        ],
        capture_output=True,
        text=True,
        timeout=1800,
    )
    assert installed.returncode == 0, installed.stderr[-3000:]
    return folder


@pytest.mark.slow
def test_a_fresh_environment_runs_touchbench_and_loads_an_old_model(
    wheel: Path, tmp_path: Path
) -> None:
    """One environment for every check: pip installs its dependencies from the index, which
    is the slow part, and test workers would each build their own for separate tests."""
    environment = _fresh_environment(wheel, tmp_path / "venv")
    # a PYTHONPATH of the outer run (a work tree's) would put `app` back on the path
    clean = {key: value for key, value in os.environ.items() if key != "PYTHONPATH"}

    def run(*args: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run(
            args, capture_output=True, text=True, cwd=tmp_path, env=clean, timeout=300
        )

    version = run(str(environment / "bin" / "touchbench"), "--version")
    assert version.returncode == 0, version.stderr
    assert version.stdout.startswith("touchbench ")

    for name in PARTS:  # nothing but touchbench: no `app` to shadow a researcher's own
        imported = run(str(environment / "bin" / "python"), "-c", f"import {name}")
        assert imported.returncode == 1 and f"No module named '{name}'" in imported.stderr

    database = tmp_path / "touchbench.db"
    with gzip.open(BEFORE / "store.db.gz") as packed, database.open("wb") as unpacked:
        shutil.copyfileobj(packed, unpacked)
    touchbench = [str(environment / "bin" / "touchbench"), "--db", f"sqlite:///{database}"]
    data = tmp_path / "robot.arff"
    exported = run(*touchbench, "export", "robot", "-o", str(data))
    assert exported.returncode == 0, exported.stderr
    predicted = run(*touchbench, "predict", "old-cc", str(data), "--json")
    assert predicted.returncode == 0, predicted.stderr
    expected = json.loads((BEFORE / "predictions-old-cc.json").read_text())
    assert_same_predictions(json.loads(predicted.stdout)["predictions"], expected)
