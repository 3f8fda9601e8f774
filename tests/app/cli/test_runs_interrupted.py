"""Runs and models under interrupts, failures, concurrency and hostile stores (CLI, on SQLite
and PostgreSQL): Ctrl-C, a run whose every task fails, a second process on a running run,
cancellation, crafted model artifacts, and ordinary mistakes that must not look like crashes."""

from __future__ import annotations

import json
import os
import pickle
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from sqlalchemy import create_engine, event, text

from tests.support.cli_runner import run_cli
from tests.support.gate import Gate
from tests.support.processes import bench_process, scalar, store_engine, wait_for_results
from tests.support.synthetic import touch_arff
from touchbench.app.store.database import Store
from touchbench.app.store.models import list_models

ROOT = Path(__file__).resolve().parents[3]


def _import(capsys: pytest.CaptureFixture[str], url: str, path: Path, name: str) -> None:
    result = run_cli(capsys, url, "import", str(path), "--name", name)
    assert result.code == 0, result.err


#: 10 tasks of the gate entry: each fit waits until the test lets it through.
GATED = ["--target", "gesture", "--classifiers", "gate", "--folds", "10"]


@pytest.mark.parametrize(
    ("store_url", "sig", "ignore_sigint", "code"),
    [
        ("sqlite", signal.SIGINT, False, 130),
        # a script's `touchbench bench ... &`: SIGINT ignored
        ("sqlite", signal.SIGINT, True, 130),
        # the stores differ in how the interrupted run's rows are written, not in how the
        # signal arrives: one signal on both is enough
        ("sqlite", signal.SIGTERM, False, 143),
        ("postgresql", signal.SIGTERM, False, 143),
    ],
    ids=["sqlite-ctrl-c", "sqlite-ctrl-c-in-background", "sqlite-sigterm", "postgresql-sigterm"],
    indirect=["store_url"],
)
@pytest.mark.slow
def test_an_interrupt_keeps_the_folds_and_resume_finishes(
    capsys: pytest.CaptureFixture[str],
    store_url: str,
    tmp_path: Path,
    sig: signal.Signals,
    ignore_sigint: bool,
    code: int,
) -> None:
    _import(capsys, store_url, touch_arff(tmp_path / "t.arff", n=300), "touch")
    gate = Gate(tmp_path / "gate")
    child = bench_process(store_url, gate, "touch", *GATED, ignore_sigint=ignore_sigint)
    gate.let_through(3)
    wait_for_results(store_url, child, 3)
    gate.wait_started(4)  # the fourth task waits at the gate: the signal comes mid-task
    child.send_signal(sig)
    _, err = child.communicate(timeout=60)
    message = err.decode()
    assert child.returncode == code, message
    assert "run 1 interrupted" in message and "touchbench bench --resume 1" in message
    assert "Traceback" not in message
    assert scalar(store_url, "SELECT status FROM runs WHERE id = 1") == "interrupted"
    assert scalar(store_url, "SELECT count(*) FROM fold_results") == 3
    assert "3 of 10 tasks are stored" in message
    gate.open()
    resumed = subprocess.run(
        [
            sys.executable,
            "-m",
            "touchbench.app.cli.main",
            "--db",
            store_url,
            "bench",
            "--resume",
            "1",
        ],
        cwd=ROOT,
        env={**os.environ, **gate.environment()},
        capture_output=True,
        timeout=300,
    )
    assert resumed.returncode == 0, resumed.stderr.decode()
    assert scalar(store_url, "SELECT status FROM runs WHERE id = 1") == "done"
    assert scalar(store_url, "SELECT count(*) FROM fold_results") == 10


def test_a_run_whose_every_task_fails_is_failed_and_says_why(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    _import(capsys, store_url, touch_arff(tmp_path / "t.arff"), "touch")
    result = run_cli(
        capsys,
        store_url,
        "bench",
        "touch",
        "--target",
        "gesture",
        "-c",
        "rf,nb",
        "--folds",
        "2",
        "--timeout",
        "0.001",
    )
    assert result.code == 1
    assert "run 1 failed: all 4 tasks failed" in result.err and "timed out" in result.err
    run = run_cli(capsys, store_url, "runs", "--json").json()["runs"][0]
    assert (run["status"], run["tasks_done"], run["tasks_failed"]) == ("failed", 4, 4)
    assert run["error"].startswith("all 4 tasks failed")
    board = run_cli(capsys, store_url, "leaderboard", "1", "--json")
    assert board.code == 0, board.err
    report = board.json()
    assert report["status"] == "failed" and report["baseline"] is None
    assert {row["classifier"] for row in report["leaderboard"]} == {"rf", "nb"}
    assert all(
        row["n_failed"] == 2 and "timed out" in row["errors"][0] for row in report["leaderboard"]
    )
    table = run_cli(capsys, store_url, "leaderboard", "1")
    assert table.code == 0 and "timed out" in table.out


def test_a_running_run_is_not_resumed_twice_and_can_be_cancelled(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    _import(capsys, store_url, touch_arff(tmp_path / "t.arff", n=300), "touch")
    gate = Gate(tmp_path / "gate")
    child = bench_process(store_url, gate, "touch", *GATED)
    try:
        gate.let_through(2)
        wait_for_results(store_url, child, 2)
        gate.wait_started(3)
        second = run_cli(capsys, store_url, "bench", "--resume", "1")
        assert second.code == 2
        assert "run 1 is being executed by" in second.err and "touchbench cancel 1" in second.err
        cancel = run_cli(capsys, store_url, "cancel", "1")
        assert cancel.code == 0, cancel.err
        _, err = child.communicate(timeout=60)
    finally:
        if child.poll() is None:
            child.kill()
    assert child.returncode == 1, err.decode()
    assert "run 1 cancelled: 2 of 10 tasks are stored" in err.decode()
    assert scalar(store_url, "SELECT status FROM runs WHERE id = 1") == "cancelled"
    again = run_cli(capsys, store_url, "cancel", "1")
    assert again.code == 2 and "already cancelled" in again.err


def test_bench_refusals_exit_2_and_leave_no_run(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    singles = tmp_path / "singles.arff"
    singles.write_text(
        "@relation s\n@attribute x numeric\n@attribute c {a,b,c}\n@data\n1,a\n2,b\n3,c\n"
    )
    _import(capsys, store_url, singles, "singles")
    _import(capsys, store_url, touch_arff(tmp_path / "t.arff"), "touch")
    cases = [
        (["singles", "-c", "zeror"], "fold"),
        (["touch", "--target", "gesture", "-c", "nb", "--scheduler", "garbage"], "not a Dask"),
        (["touch", "--target", "gesture", "-c", "nb", "--jobs", "999"], "--oversubscribe"),
        (["touch", "--target", "gesture", "-c", "nb", "--max-memory", "-1"], "--max-memory"),
    ]
    for args, message in cases:
        result = run_cli(capsys, store_url, "bench", *args)
        assert result.code == 2, (args, result.err)
        assert message in result.err and "Traceback" not in result.err
        assert len(result.err.strip().splitlines()) == 1, result.err
    assert run_cli(capsys, store_url, "runs", "--json").json() == {"runs": []}


def test_an_unreachable_scheduler_leaves_no_run(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr("touchbench.benchmark.run.dask_backend.CONNECT_TIMEOUT", "1s")
    url = f"sqlite:///{tmp_path / 's.db'}"
    _import(capsys, url, touch_arff(tmp_path / "t.arff"), "touch")
    result = run_cli(
        capsys,
        url,
        "bench",
        "touch",
        "--target",
        "gesture",
        "-c",
        "nb",
        "--scheduler",
        "tcp://127.0.0.1:9",
    )
    assert result.code == 2 and "cannot reach the Dask scheduler" in result.err
    assert run_cli(capsys, url, "runs", "--json").json() == {"runs": []}


class _Touch:
    def __init__(self, path: Path) -> None:
        self.path = path

    def __reduce__(self) -> tuple[object, tuple[object, ...]]:
        return (Path.touch, (self.path,))


def test_a_crafted_artifact_with_a_matching_digest_runs_nothing(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    import hashlib

    data = touch_arff(tmp_path / "t.arff")
    _import(capsys, store_url, data, "touch")
    trained = run_cli(capsys, store_url, "train", "touch", "-c", "nb", "--target", "gesture")
    assert trained.code == 0, trained.err
    marker = tmp_path / "pwned"
    crafted = pickle.dumps(_Touch(marker))
    engine = store_engine(store_url)
    with engine.begin() as connection:
        connection.execute(text("UPDATE model_artifacts SET artifact = :a"), {"a": crafted})
        connection.execute(
            text("UPDATE models SET sha256 = :s, size_bytes = :n"),
            {"s": hashlib.sha256(crafted).hexdigest(), "n": len(crafted)},
        )
    engine.dispose()
    result = run_cli(capsys, store_url, "predict", "touch-nb", str(data))
    assert result.code == 2
    assert "not a skops artifact" in result.err
    assert not marker.exists()


def test_listing_models_reads_no_artifact(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    _import(capsys, store_url, touch_arff(tmp_path / "t.arff"), "touch")
    for classifier in ("nb", "j48"):
        assert (
            run_cli(
                capsys, store_url, "train", "touch", "-c", classifier, "--target", "gesture"
            ).code
            == 0
        )
    store = Store(store_url)
    statements: list[str] = []
    event.listen(
        store.engine, "before_cursor_execute", lambda *args: statements.append(str(args[2]))
    )
    try:
        assert [m.name for m in list_models(store)] == ["touch-nb", "touch-j48"]
    finally:
        store.dispose()
    assert statements and not any("artifact" in statement for statement in statements)


def test_predict_says_what_it_changed(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    _import(capsys, store_url, touch_arff(tmp_path / "t.arff"), "touch")
    assert run_cli(capsys, store_url, "train", "touch", "-c", "nb", "--target", "gesture").code == 0
    odd = tmp_path / "odd.arff"
    odd.write_text(
        "@relation odd\n@attribute gesture {tap, poke}\n@attribute place {head, arm}\n"
        "@attribute f0 numeric\n@attribute f1 numeric\n@attribute f2 numeric\n"
        "@attribute f3 numeric\n@attribute mic {left, right, elbow}\n@data\n"
        "tap,head,0,0,0,0,left\npoke,arm,4,2,0,0,elbow\npoke,arm,4,2,0,0,elbow\n"
    )
    result = run_cli(capsys, store_url, "predict", "touch-nb", str(odd), "--json")
    assert result.code == 0, result.err
    warnings = result.json()["warnings"]
    assert any("attribute 'mic'" in w and "'elbow'" in w and "2 instance(s)" in w for w in warnings)
    assert any("target 'gesture'" in w and "'poke'" in w and "misses" in w for w in warnings)
    table = run_cli(capsys, store_url, "predict", "touch-nb", str(odd))
    assert "warning:" in table.err and "'elbow'" in table.err


def test_stores_that_are_not_ours_are_refused_untouched(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    import sqlite3

    foreign = tmp_path / "other.db"
    with sqlite3.connect(foreign) as connection:
        connection.execute("CREATE TABLE notes (body TEXT)")
    before = foreign.read_bytes()
    result = run_cli(capsys, f"sqlite:///{foreign}", "datasets")
    assert result.code == 2 and "another application's SQLite database" in result.err
    assert foreign.read_bytes() == before
    assert not Path(f"{foreign}-wal").exists()
    text_file = tmp_path / "notes.txt"
    text_file.write_text("hello\n")
    result = run_cli(capsys, f"sqlite:///{text_file}", "datasets")
    assert result.code == 2 and "is not a SQLite database" in result.err
    assert text_file.read_text() == "hello\n"


def test_an_old_store_migrates_and_finished_runs_become_done(tmp_path: Path) -> None:
    from alembic import command
    from alembic.config import Config

    from touchbench.app.store.database import MIGRATIONS
    from touchbench.app.store.reading import HEAD_REVISION

    url = f"sqlite:///{tmp_path / 'old.db'}"
    engine = create_engine(url)
    config = Config()
    config.set_main_option("script_location", str(MIGRATIONS))
    with engine.begin() as connection:
        config.attributes["connection"] = connection
        command.upgrade(config, "0002")
        connection.execute(
            text(
                "INSERT INTO datasets (id, name, relation, schema, target_names, n_instances, "
                "n_attributes, sparse, sha256, created_at) VALUES (1, 'd', 'd', '{}', '[]', 0, "
                "0, 0, 'x', '2026-01-01')"
            )
        )
        connection.execute(
            text(
                "INSERT INTO runs (id, dataset_id, kind, targets, classifiers, config, status, "
                "created_at) VALUES (1, 1, 'multiclass', '[]', '[]', '{}', 'finished', "
                "'2026-01-01')"
            )
        )
    engine.dispose()
    store = Store(url)
    try:
        assert scalar(url, "SELECT status FROM runs") == "done"
        assert scalar(url, "SELECT version_num FROM alembic_version") == HEAD_REVISION
    finally:
        store.dispose()


def test_every_help_page_reads_well(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    import typer

    from touchbench.app.cli.main import app

    url = f"sqlite:///{tmp_path / 'h.db'}"
    names = [c.name for c in typer.main.get_command(app).commands.values()]  # type: ignore[attr-defined]
    assert {"bench", "cancel", "import", "predict", "train", "leaderboard"} <= set(names)
    for name in [None, *names]:
        result = run_cli(capsys, url, *([name] if name else []), "--help")
        assert result.code == 0, (name, result.err)
        for ugly in ("<bool>", "{file}", "<list", "<path>", "<int>", "<float>", "<str>"):
            assert ugly not in result.out.lower(), (name, ugly, result.out)
    version = run_cli(capsys, url, "--version")
    assert version.code == 0 and version.out.startswith("touchbench ")


def test_error_lines_are_not_wrapped(tmp_path: Path) -> None:
    long_name = "a" * 150
    environment = {**os.environ, "COLUMNS": "60"}
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "touchbench.app.cli.main",
            "--db",
            f"sqlite:///{tmp_path / 'w.db'}",
            "show",
            long_name,
        ],
        cwd=ROOT,
        env=environment,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 2
    assert len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert json.dumps(done.stderr)  # printable


def test_processes_opening_a_new_store_at_once_migrate_it_once(store_url: str) -> None:
    environment = {**os.environ, "PYTHONPATH": str(ROOT)}
    processes = [
        subprocess.Popen(
            [
                sys.executable,
                "-m",
                "touchbench.app.cli.main",
                "--db",
                store_url,
                "datasets",
                "--json",
            ],
            cwd=ROOT,
            env=environment,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for _ in range(4)
    ]
    results = [(p.wait(120), *p.communicate()) for p in processes]
    assert [code for code, _, _ in results] == [0, 0, 0, 0], results
    assert all(json.loads(out) == {"datasets": []} for _, out, _ in results)
    assert scalar(store_url, "SELECT count(*) FROM alembic_version") == 1


def test_weka_command_lines_run_and_export_as_weka_wrote_them(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    _import(capsys, store_url, touch_arff(tmp_path / "t.arff"), "touch")
    result = run_cli(
        capsys,
        store_url,
        "bench",
        "touch",
        "--target",
        "gesture",
        "--weka",
        "weka.classifiers.trees.J48 -C 0.1 -M 5",
        "--weka",
        "NaiveBayes -K",
        "--folds",
        "3",
        "--json",
    )
    assert result.code == 0, result.err
    ids = {row["classifier"] for row in result.json()["leaderboard"]}
    assert len(ids) == 2 and "nb-kernel" in ids
    arff = run_cli(capsys, store_url, "leaderboard", "1", "--format", "arff")
    assert "weka.classifiers.trees.J48,'-C 0.1 -M 5'" in arff.out.replace('"', "'")
    refused = run_cli(
        capsys, store_url, "bench", "touch", "--target", "gesture", "--weka", "J48 -B"
    )
    assert refused.code == 2 and "option '-B'" in refused.err
