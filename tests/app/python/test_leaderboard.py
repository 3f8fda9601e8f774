"""The Python Leaderboard read from a real store: the CLI's rows and marks, a DataFrame,
the CLI's plots, and a display that escapes every name."""

from __future__ import annotations

import copy
import math
from pathlib import Path
from typing import Any

import pytest
from matplotlib.figure import Figure

from tests.app.cli_runner import run_cli
from tests.app.synthetic import touch_arff
from touchbench.app.errors import AppError
from touchbench.app.python.leaderboard import Leaderboard
from touchbench.app.python.sources import StoreSource, stored_leaderboard
from touchbench.app.store.database import Store


@pytest.fixture
def ran(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> tuple[str, dict[str, Any]]:
    """A finished run of three classifiers on 3 folds, and the CLI's JSON of it."""
    url = f"sqlite:///{tmp_path / 'touchbench.db'}"
    data = touch_arff(tmp_path / "t.arff", n=90)
    assert run_cli(capsys, url, "import", str(data), "--name", "touch").code == 0
    bench = ("bench", "touch", "--target", "gesture", "-c", "nb,zeror,j48", "--folds", "3")
    assert run_cli(capsys, url, *bench).code == 0
    cli = run_cli(capsys, url, "leaderboard", "1", "--json")
    assert cli.code == 0, cli.err
    return url, cli.json()


def test_the_stored_leaderboard_is_the_clis_with_its_plots(
    ran: tuple[str, dict[str, Any]], capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    url, cli = ran
    board = stored_leaderboard(Store(url), 1)
    assert board.schema.to_json() == cli
    assert board.best == board.best_row.classifier == cli["leaderboard"][0]["classifier"]  # type: ignore[union-attr]

    frame = board.to_pandas()
    assert list(frame.index) == [row["classifier"] for row in cli["leaderboard"]]
    assert list(frame.columns[:4]) == ["rank", "mark", "f1_weighted_mean", "f1_weighted_std"]
    assert frame["mark"].iloc[0] == "(base)" and frame.loc["zeror", "mark"] == "*"
    assert (frame["folds"] == 3).all() and (frame["n_failed"] == 0).all()
    for row in cli["leaderboard"]:
        accuracy = row["metrics"]["accuracy"]
        assert frame.loc[row["classifier"], "accuracy_mean"] == pytest.approx(accuracy["mean"])

    folds = board.fold_scores()
    assert folds.shape == (3, 3) and list(folds.columns) == list(frame.index)
    assert folds.mean().to_dict() == pytest.approx(frame["f1_weighted_mean"].to_dict())

    # the same figures as `touchbench plot`, whose SVG text is the same
    from touchbench.app.reports.plots import svg_text

    for kind in ("cd", "folds", "confusion"):
        figure = board.plot(kind)
        assert isinstance(figure, Figure)
        out = tmp_path / f"{kind}.svg"
        drawn = run_cli(capsys, url, "plot", "1", "--kind", kind, "-o", str(out))
        assert drawn.code == 0, drawn.err
        assert svg_text(figure) == out.read_text(), kind

    with pytest.raises(AppError, match="kind: 'roc' is not one of cd, folds, confusion"):
        board.plot("roc")  # type: ignore[arg-type]
    with pytest.raises(AppError, match="classifier: goes with kind 'confusion'"):
        board.plot("folds", classifier="nb")
    with pytest.raises(AppError, match="run 1 has no classifier 'rf'"):
        board.plot("confusion", classifier="rf")
    with pytest.raises(AppError, match="plots need the store or the service"):
        Leaderboard(board.schema).plot("cd")


def test_the_display_escapes_every_name(ran: tuple[str, dict[str, Any]]) -> None:
    url, cli = ran
    hostile = copy.deepcopy(cli)
    hostile["dataset"] = "<b>touch & go</b>"
    hostile["leaderboard"][1]["classifier"] = '<script>alert("x")</script>'
    hostile["leaderboard"][1]["errors"] = ["<img src=x onerror=alert(1)>"]
    hostile["leaderboard"][1]["n_failed"] = 1
    hostile["notes"] = ["<i>note</i>"]
    board = Leaderboard.from_json(hostile, StoreSource(Store(url)))
    html = board._repr_html_()
    for raw in ("<script>", "<img", "<b>", "<i>"):
        assert raw not in html
    assert "&lt;script&gt;alert(&quot;x&quot;)&lt;/script&gt;" in html
    assert "&lt;b&gt;touch &amp; go&lt;/b&gt;" in html
    assert "1 failed: &lt;img src=x onerror=alert(1)&gt;" in html
    assert '<td style="text-align:left">(base)</td>' in html
    text = repr(board)
    assert '<script>alert("x")</script>' in text and "notes" in text.splitlines()[1]


def test_no_best_without_a_score(ran: tuple[str, dict[str, Any]]) -> None:
    _, cli = ran
    failed = copy.deepcopy(cli)
    failed["baseline"] = None
    for row in failed["leaderboard"]:
        row["metrics"] = {name: {"mean": None, "std": None} for name in row["metrics"]}
    board = Leaderboard.from_json(failed)
    assert board.best is None and board.best_row is None
    assert math.isnan(board.to_pandas()["f1_weighted_mean"].iloc[0])
    assert "no task of run 1 succeeded" in repr(board)
    assert board.mark(board.rows[0]) == board.rows[0].mark
