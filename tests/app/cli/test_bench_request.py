"""`touchbench bench` builds one request (BenchRequest) from its options: what a run
cannot honour is refused naming its option, in one line, exit 2, before a run row exists
(on SQLite); what it takes is stored with the run (on SQLite and PostgreSQL)."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.support.cli_runner import CliResult, run_cli, run_cli_captured
from tests.support.rows import count_rows
from tests.support.stores import copy_sqlite
from tests.support.synthetic import position_arff, touch_arff
from touchbench.app.cli.bench import BENCH_OPTIONS
from touchbench.app.schemas.runs import BenchHereRequest, BenchRequest
from touchbench.app.services.runs import NoResultsError, create_run, run_leaderboard
from touchbench.app.store.database import Store


def _imported(capsys: pytest.CaptureFixture[str], url: str, tmp_path: Path) -> str:
    for path, name in (
        (touch_arff(tmp_path / "touch.arff", n=60), "touch"),
        (position_arff(tmp_path / "contact.arff"), "contact"),
    ):
        result = run_cli(capsys, url, "import", str(path), "--name", name)
        assert result.code == 0, result.err
    return url


@pytest.fixture
def db(capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path) -> str:
    """The two data sets, on SQLite then on PostgreSQL: for what the run stores."""
    return _imported(capsys, store_url, tmp_path)


@pytest.fixture(scope="module")
def sqlite_template(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A SQLite store holding the two data sets, imported once for the module."""
    folder = tmp_path_factory.mktemp("bench-request")
    url = f"sqlite:///{folder / 'touchbench.db'}"
    for path, name in (
        (touch_arff(folder / "touch.arff", n=60), "touch"),
        (position_arff(folder / "contact.arff"), "contact"),
    ):
        imported = run_cli_captured(url, "import", str(path), "--name", name)
        assert imported.code == 0, imported.err
    return folder / "touchbench.db"


@pytest.fixture
def sqlite_db(sqlite_store_url: str, sqlite_template: Path) -> str:
    """The two data sets on SQLite only: for what is refused before a run exists (a copy
    of the module's template, the test's own)."""
    copy_sqlite(sqlite_template, Path(sqlite_store_url.removeprefix("sqlite:///")))
    return sqlite_store_url


def _refused(result: CliResult, line: str) -> None:
    assert result.code == 2, result.err
    assert result.err.strip() == f"touchbench: error: {line}", result.err


#: Each option that a benchmark of every target on its own cannot honour.
INDEPENDENT_DROPS = [
    (["--target", "gesture"], "--target", "benchmarks every target"),
    (["--weka", "weka.classifiers.trees.J48 -C 0.1"], "--weka", "runs the catalogue's"),
    (["--position", "f0,f1"], "--position", "with no coordinates"),
    (["--tune"], "--tune", "plain classifiers"),
    (["--budget", "5"], "--budget", "plain classifiers"),
    (["--stack", "2"], "--stack", "plain classifiers"),
    (["--metric", "accuracy"], "--metric", "by weighted F1"),
    (["--baseline", "zeror"], "--baseline", "by weighted F1"),
]


@pytest.mark.parametrize(("extra", "option", "reason"), INDEPENDENT_DROPS)
def test_what_independent_runs_cannot_honour_is_refused_naming_the_option(
    capsys: pytest.CaptureFixture[str], sqlite_db: str, extra: list[str], option: str, reason: str
) -> None:
    result = run_cli(capsys, sqlite_db, "bench", "touch", "--independent", "-c", "zeror,nb", *extra)
    assert result.code == 2, result.err
    assert result.err.startswith(f"touchbench: error: {option}: is not used with --independent")
    assert reason in result.err and len(result.err.strip().splitlines()) == 1, result.err
    assert count_rows(sqlite_db, "runs") == 0


def test_the_issues_independent_command_is_refused_at_its_first_dropped_option(
    capsys: pytest.CaptureFixture[str], sqlite_db: str
) -> None:
    args = ["--weka", "J48", "--position", "f0,f1", "--budget", "5"]
    result = run_cli(capsys, sqlite_db, "bench", "touch", "--independent", *args)
    _refused(
        result,
        "--weka: is not used with --independent, which runs the catalogue's multi-class "
        "classifiers on each target",
    )
    regression = run_cli(capsys, sqlite_db, "bench", "contact", "--independent", "-c", "ridge")
    assert regression.code == 2
    assert regression.err.startswith("touchbench: error: --independent: compares targets")
    assert count_rows(sqlite_db, "runs") == 0


@pytest.mark.parametrize(
    ("extra", "line"),
    [
        (["--max-memory", "1e15"], "--max-memory: Input should be less than or equal to 1048576"),
        (["--max-memory", "1e308"], "--max-memory: Input should be less than or equal to 1048576"),
        (["--max-memory", "inf"], "--max-memory: Input should be a finite number"),
        (["--max-memory", "0.5"], "--max-memory: Input should be greater than or equal to 1"),
        (["--timeout", "-1"], "--timeout: Input should be greater than or equal to 0"),
        (["--timeout", "1e9"], "--timeout: Input should be less than or equal to 604800"),
        (["--folds", "1"], "--folds: Input should be greater than or equal to 2"),
        (["--repeats", "0"], "--repeats: Input should be greater than or equal to 1"),
        (["--seed", "-1"], "--seed: Input should be greater than or equal to 0"),
        (["--budget", "5"], "--budget: is only meaningful with --tune"),
        (["--suite", "fast"], "--suite: is not used with --classifiers: give one or the other"),
        (
            ["--baseline", "rf"],
            "--baseline: 'rf' is not a classifier of this run (classifiers: zeror, nb)",
        ),
        (["--weka", "weka.classifiers.Nope"], "--weka: "),
        (["--target", "nope"], "--target: no attribute named 'nope'"),
    ],
)
def test_run_options_out_of_bounds_are_refused_before_a_run_exists(
    capsys: pytest.CaptureFixture[str], sqlite_db: str, extra: list[str], line: str
) -> None:
    result = run_cli(
        capsys, sqlite_db, "bench", "touch", "--target", "gesture", "-c", "zeror,nb", *extra
    )
    assert result.code == 2, result.err
    assert result.err.startswith(f"touchbench: error: {line}"), result.err
    assert len(result.err.strip().splitlines()) == 1 and "Traceback" not in result.err
    assert count_rows(sqlite_db, "runs") == 0


@pytest.mark.parametrize(
    ("extra", "line"),
    [
        (["--stack", "1"], "--stack: works on classification runs; the targets here are numeric"),
        (["--tune"], "--tune: works on classification runs; the targets here are numeric"),
        (["--metric", "accuracy"], "--metric: 'accuracy' is not a regression metric"),
    ],
)
def test_what_a_regression_cannot_take_names_its_option(
    capsys: pytest.CaptureFixture[str], sqlite_db: str, extra: list[str], line: str
) -> None:
    result = run_cli(capsys, sqlite_db, "bench", "contact", "-c", "ridge,linear", *extra)
    assert result.code == 2, result.err
    assert result.err.startswith(f"touchbench: error: {line}"), result.err
    assert count_rows(sqlite_db, "runs") == 0


def test_a_resumed_run_keeps_its_options_and_refuses_new_ones(
    capsys: pytest.CaptureFixture[str], db: str
) -> None:
    args = ["bench", "touch", "--target", "gesture", "-c", "zeror,nb", "-k", "3"]
    first = run_cli(capsys, db, *args, "--timeout", "0", "--metric", "accuracy", "--json")
    assert first.code == 0, first.err
    assert first.json()["metric"] == "accuracy"
    run = run_cli(capsys, db, "runs", "--json").json()["runs"][0]
    assert run["config"]["timeout"] is None  # 0: no limit
    assert (run["config"]["metric"], run["config"]["baseline"]) == ("accuracy", None)
    for extra, option in ((["--folds", "5"], "--folds"), (["--timeout", "0"], "--timeout")):
        again = run_cli(capsys, db, "bench", "--resume", "1", *extra)
        assert again.code == 2, again.err
        assert f"{option} is kept by the run; drop it with --resume" in again.err
    board = run_cli(capsys, db, "leaderboard", "1", "--json")
    assert board.code == 0 and board.json()["metric"] == "accuracy"  # what the run asked for
    other = run_cli(capsys, db, "leaderboard", "1", "--metric", "f1_weighted", "--json")
    assert other.json()["metric"] == "f1_weighted"
    assert count_rows(db, "runs") == 1


def test_independent_runs_take_the_request_and_check_every_target_first(
    capsys: pytest.CaptureFixture[str], sqlite_db: str, tmp_path: Path
) -> None:
    lopsided = tmp_path / "lopsided.arff"
    rows = "".join(f"{i},{'ab'[i % 2]},p\n" for i in range(12))
    lopsided.write_text(
        "@relation 'lopsided: -C -2'\n@attribute x numeric\n@attribute a {a,b}\n"
        f"@attribute b {{p,q}}\n@data\n{rows}"
    )
    assert run_cli(capsys, sqlite_db, "import", str(lopsided)).code == 0
    refused = run_cli(
        capsys, sqlite_db, "bench", "lopsided", "--independent", "-c", "zeror", "-k", "3"
    )
    assert refused.code == 2 and "target 'b' has a single class" in refused.err, refused.err
    assert count_rows(sqlite_db, "runs") == 0  # not even target a's run
    done = run_cli(
        capsys, sqlite_db, "bench", "touch", "--independent", "-c", "zeror,nb", "-k", "3", "-r", "2"
    )
    assert done.code == 0, done.err
    runs = run_cli(capsys, sqlite_db, "runs", "--json").json()["runs"]
    assert [r["targets"] for r in runs] == [["gesture"], ["place"]]
    assert all((r["config"]["folds"], r["config"]["repeats"]) == (3, 2) for r in runs)
    assert all(r["config"]["timeout"] == 600 for r in runs)  # the request's default


def test_a_run_without_results_says_how_to_carry_it_out_in_the_adapters_words(
    capsys: pytest.CaptureFixture[str], sqlite_db: str
) -> None:
    store = Store(sqlite_db)
    try:
        request = BenchRequest(dataset="touch", target="gesture", classifiers=["nb"], folds=3)
        run = create_run(store, request)
        queued = run_cli(capsys, sqlite_db, "leaderboard", str(run.id))
        _refused(queued, f"run {run.id} has no results yet (it waits for a worker)")
        assert run_cli(capsys, sqlite_db, "cancel", str(run.id)).code == 0
        cancelled = run_cli(capsys, sqlite_db, "leaderboard", str(run.id))
        _refused(
            cancelled,
            f"run {run.id} has no results yet (it is cancelled; "
            f"`touchbench bench --resume {run.id}` carries it out)",
        )
        with pytest.raises(NoResultsError) as service:
            run_leaderboard(store, run.id)
        assert str(service.value) == (
            f"run {run.id} has no results yet (it is cancelled; resuming it carries it out)"
        )
    finally:
        store.dispose()


def test_each_field_of_the_requests_is_one_option_of_bench(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    """The command's signature declares the options; the table the CLI names refused
    fields by is read from it, and covers every field of both requests."""
    fields = set(BenchRequest.model_fields) | set(BenchHereRequest.model_fields) - {"bench"}
    assert fields <= set(BENCH_OPTIONS)
    shown = run_cli(capsys, f"sqlite:///{tmp_path / 'h.db'}", "bench", "--help")
    assert shown.code == 0
    for field in fields - {"dataset"}:
        assert BENCH_OPTIONS[field] in shown.out, field
    both = run_cli(
        capsys,
        f"sqlite:///{tmp_path / 'h.db'}",
        "bench",
        "touch",
        "--independent",
        "--ablate-groups",
        "channel",
    )
    _refused(both, "--ablate-groups: is not used with --independent")
