"""Asking for a part whose extra is not installed: one line naming the extra, exit 2 on the
command line, a 4xx on the service; ``classifiers`` marks what is not installed.

Each case runs real processes (the CLI, ``touchbench serve`` and its workers) whose
imports cannot find the extra's libraries: ``tests/without_extras/sitecustomize.py`` hides
them, as if ``pip install touchbench`` had installed the core alone.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from tests.support.cli_runner import run_cli
from tests.support.service import Server
from tests.support.stores import copy_sqlite

ROOT = Path(__file__).resolve().parents[3]
HIDER = ROOT / "tests" / "without_extras"
EXTRA_MODULES = {
    "neural": "torch,safetensors",
    "boosting": "lightgbm,catboost",
    "sequences": "aeon",
    "onnx": "onnx,skl2onnx,onnxmltools,onnxruntime",
}


def _arff(path: Path) -> Path:
    rng = np.random.default_rng(0)
    rows = [
        f"{a:.4f},{b:.4f},{c:.4f},{'tap' if a + b > 1 else 'slap'}"
        for a, b, c in rng.random((40, 3))
    ]
    text = "@relation touches\n" + "".join(f"@attribute f{i} numeric\n" for i in range(3))
    path.write_text(text + "@attribute gesture {tap,slap}\n@data\n" + "\n".join(rows) + "\n")
    return path


def _environment(hidden: str) -> dict[str, str]:
    environment = dict(os.environ)
    path = environment.get("PYTHONPATH")
    environment["PYTHONPATH"] = os.pathsep.join(filter(None, [str(HIDER), path]))
    environment["HIDE_MODULES_FOR_TEST"] = hidden
    environment.pop("TOUCHBENCH_DATABASE_URL", None)
    return environment


def _touchbench(tmp_path: Path, *args: str, hidden: str = "") -> subprocess.CompletedProcess[str]:
    database = f"sqlite:///{tmp_path / 'touchbench.db'}"
    return subprocess.run(
        [sys.executable, "-m", "touchbench", "--db", database, *args],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env=_environment(hidden),
        timeout=300,
    )


def _one_line_naming(result: subprocess.CompletedProcess[str], extra: str) -> None:
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert f"'{extra}' extra" in lines[0]
    assert f"pip install 'touchbench[{extra}]'" in lines[0]
    assert "Traceback" not in result.stderr


def _url(folder: Path) -> str:
    """The store ``_touchbench`` uses in ``folder``."""
    return f"sqlite:///{folder / 'touchbench.db'}"


@pytest.fixture(scope="module")
def imported_once(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder with ``touches.arff`` and a store it was imported into (by the CLI, as a
    process), made once for the module: each test gets a copy (:func:`stored`)."""
    folder = tmp_path_factory.mktemp("extras")
    imported = _touchbench(folder, "import", str(_arff(folder / "touches.arff")))
    assert imported.returncode == 0, imported.stderr
    return folder


@pytest.fixture
def stored(imported_once: Path, tmp_path: Path) -> Path:
    """A store with the data set ``touches`` (a copy of the module's: the tests add to it)."""
    shutil.copy(imported_once / "touches.arff", tmp_path / "touches.arff")
    copy_sqlite(imported_once / "touchbench.db", tmp_path / "touchbench.db")
    return tmp_path


def test_the_hider_hides(tmp_path: Path) -> None:
    done = subprocess.run(
        [sys.executable, "-c", "import torch"],
        capture_output=True,
        text=True,
        env=_environment("torch"),
    )
    assert done.returncode == 1 and "No module named 'torch'" in done.stderr


@pytest.mark.parametrize(
    ("classifier", "extra"),
    [
        ("bilstm", "neural"),
        ("lgbm", "boosting"),
        ("catboost", "boosting"),
        ("minirocket", "sequences"),
    ],
)
@pytest.mark.slow
def test_bench_names_the_missing_extra(
    capsys: pytest.CaptureFixture[str], stored: Path, classifier: str, extra: str
) -> None:
    result = _touchbench(
        stored, "bench", "touches", "-c", f"rf,{classifier}", hidden=EXTRA_MODULES[extra]
    )
    _one_line_naming(result, extra)
    assert f"'{classifier}'" in result.stderr and "--classifiers" in result.stderr
    runs = run_cli(capsys, _url(stored), "runs", "--json")  # in this process: hides nothing
    assert runs.json()["runs"] == []  # nothing was stored


def test_classifiers_marks_what_is_not_installed(tmp_path: Path) -> None:
    listed = _touchbench(tmp_path, "classifiers", "--json", hidden=EXTRA_MODULES["boosting"])
    assert listed.returncode == 0, listed.stderr
    entries = {entry["id"]: entry for entry in json.loads(listed.stdout)["classifiers"]}
    assert entries["lgbm"]["installed"] is False and entries["lgbm"]["extras"] == ["boosting"]
    assert entries["catboost"]["installed"] is False
    assert entries["rf"]["installed"] is True and entries["rf"]["extras"] == []
    assert entries["bilstm"]["installed"] is True and entries["bilstm"]["extras"] == ["neural"]
    table = _touchbench(tmp_path, "classifiers", hidden=EXTRA_MODULES["boosting"])
    assert table.returncode == 0, table.stderr
    rows = {line.split("│")[1].strip(): line for line in table.stdout.splitlines() if "│" in line}
    assert "✗boosting" in rows["lgbm"] and "✗" not in rows["rf"]
    assert "pip install 'touchbench[boosting]'" in table.stderr
    # a suite leaves out what cannot run here
    suite = _touchbench(tmp_path, "classifiers", "--suite", "all", "--json", hidden="lightgbm")
    ids = [entry["id"] for entry in json.loads(suite.stdout)["classifiers"]]
    assert "lgbm" not in ids and "catboost" in ids


def test_a_stored_model_of_a_missing_library_names_the_extra(
    capsys: pytest.CaptureFixture[str], stored: Path
) -> None:
    # trained in this process, where nothing is hidden; predicted by a process without it
    trained = run_cli(capsys, _url(stored), "train", "touches", "-c", "catboost", "--name", "cat")
    assert trained.code == 0, trained.err
    data = str(stored / "touches.arff")
    result = _touchbench(stored, "predict", "cat", data, hidden=EXTRA_MODULES["boosting"])
    _one_line_naming(result, "boosting")


def test_onnx_export_and_engine_name_the_missing_extra(
    capsys: pytest.CaptureFixture[str], stored: Path
) -> None:
    # what hides nothing runs in this process; what hides the extra, in a process of its own
    trained = run_cli(capsys, _url(stored), "train", "touches", "-c", "logistic", "--name", "lin")
    assert trained.code == 0, trained.err
    onnx = EXTRA_MODULES["onnx"]
    _one_line_naming(
        _touchbench(stored, "export-model", "lin", "-o", "lin.onnx", hidden=onnx), "onnx"
    )
    exported = run_cli(capsys, _url(stored), "export-model", "lin", "-o", str(stored / "lin.onnx"))
    assert exported.code == 0, exported.err
    data = str(stored / "touches.arff")
    engine = _touchbench(stored, "predict", "lin", data, "--engine", "onnx", hidden=onnx)
    _one_line_naming(engine, "onnx")
    # `auto` falls back to the model itself, saying nothing
    auto = _touchbench(stored, "predict", "lin", data, "--json", hidden=onnx)
    assert auto.returncode == 0, auto.stderr
    assert json.loads(auto.stdout)["accuracy"]["gesture"] > 0.5


def test_the_service_answers_a_missing_extra_with_a_4xx(
    make_sqlite_server: Callable[..., Server],
    monkeypatch: pytest.MonkeyPatch,
    tmp_path: Path,
) -> None:
    for key, value in _environment(EXTRA_MODULES["neural"]).items():
        monkeypatch.setenv(key, value)
    server = make_sqlite_server()
    with (_arff(tmp_path / "touches.arff")).open("rb") as data:
        uploaded = server.client.post("/api/datasets", files={"file": ("touches.arff", data)})
    assert uploaded.status_code == 201, uploaded.text
    refused = server.client.post(
        "/api/runs",
        json={"dataset": "touches", "classifiers": ["rf", "bilstm"], "folds": 2},
    )
    assert refused.status_code == 422, refused.text
    error = refused.json()["error"]
    assert error["where"] == "body.classifiers"
    assert "'neural' extra" in error["message"]
    assert server.client.get("/api/runs").json()["runs"] == []
