"""The tables below a leaderboard (tuned against default, the choices per fold, a multi-target
regression's scores per target) in the HTML report and on the web page's run view, with
the same contents as ``leaderboard --json`` (small synthetic runs)."""

from __future__ import annotations

from html.parser import HTMLParser
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient

from tests.support.cli_runner import run_cli
from tests.support.synthetic import position_arff, touch_arff
from touchbench.app.main import create_app
from touchbench.app.settings import Settings


class _Tables(HTMLParser):
    """Every ``<table data-table=KEY>``: its key, caption and rows of cell texts."""

    def __init__(self) -> None:
        super().__init__()
        self.tables: list[dict[str, Any]] = []
        self._table: dict[str, Any] | None = None
        self._text: str | None = None

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        key = dict(attrs).get("data-table")
        if tag == "table" and key:
            self._table = {"key": key, "caption": "", "rows": []}
            self.tables.append(self._table)
        elif self._table is not None and tag == "tr":
            self._table["rows"].append([])
        elif self._table is not None and tag in ("td", "th", "caption"):
            self._text = ""

    def handle_endtag(self, tag: str) -> None:
        if self._table is None:
            return
        if tag == "table":
            self._table = None
        elif tag == "caption" and self._text is not None:
            self._table["caption"] = " ".join(self._text.split())
            self._text = None
        elif tag in ("td", "th") and self._text is not None:
            self._table["rows"][-1].append(self._text.strip())
            self._text = None

    def handle_data(self, data: str) -> None:
        if self._text is not None:
            self._text += data


def tables(html: str) -> list[dict[str, Any]]:
    parser = _Tables()
    parser.feed(html)
    return parser.tables


def _bench(capsys: pytest.CaptureFixture[str], db: str, *args: str) -> dict[str, Any]:
    result = run_cli(capsys, db, "bench", *args, "-k", "3", "--json")
    assert result.code == 0, result.err
    report: dict[str, Any] = result.json()
    return report


def _check_tuning(found: list[dict[str, Any]], board: dict[str, Any]) -> None:
    """The tuning tables hold the JSON's comparison and choices."""
    (comparison,) = board["tuning"]
    tuning = next(t for t in found if t["key"] == "tuning")
    assert "corrected resampled t-test" in tuning["caption"]
    header, *rows = tuning["rows"]
    assert header[:2] == ["tuned", "default"] and "p" in header
    (row,) = rows
    assert row[0] == "logistic+tuned" and row[1] == "logistic"
    assert row[header.index("p")] == f"{comparison['p']:.4f}"
    assert row[header.index("tuned mean")] == f"{comparison['tuned_mean']:.4f}"
    assert row[header.index("folds")] == "3"
    choices = next(t for t in found if t["key"] == "choices")
    header, *rows = choices["rows"]
    assert header == ["classifier", "repeat", "fold", "chosen"]
    expected = [
        ["logistic+tuned", "1", str(c["fold"] + 1), f"C={c['params']['C']:g}"]
        for c in board["choices"]
    ]
    assert rows == expected and len(rows) == 3


def _check_targets(found: list[dict[str, Any]], board: dict[str, Any]) -> None:
    """One table per target with each regressor's MAE, RMSE and R^2 on it."""
    per_target = [t for t in found if t["key"] == "target"]
    assert [t["caption"].split(" (")[0] for t in per_target] == ["target x", "target y"]
    ridge = next(r for r in board["leaderboard"] if r["classifier"] == "ridge")
    for table, target in zip(per_target, ("x", "y"), strict=True):
        header, *rows = table["rows"]
        assert header == ["classifier", "mae", "rmse", "r2"]
        assert [r[0] for r in rows] == [r["classifier"] for r in board["leaderboard"]]
        scores = ridge["metrics"]["per_target"][target]
        cells = next(r for r in rows if r[0] == "ridge")
        for cell, metric in zip(cells[1:], ("mae", "rmse", "r2"), strict=True):
            assert cell == f"{scores[metric]['mean']:.4f} ±{scores[metric]['std']:.3f}"
    assert ridge["metrics"]["per_target"]["x"]["mae"]["mean"] < 1.0  # x is linear: ridge fits


def test_report_and_web_page_show_tuning_and_per_target_tables(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    db = f"sqlite:///{tmp_path / 't.db'}"
    for path in (touch_arff(tmp_path / "touch.arff", n=90), position_arff(tmp_path / "c.arff")):
        assert run_cli(capsys, db, "import", str(path), "--json").code == 0
    tuned = _bench(
        capsys, db, "touch", "--target", "gesture", "-c", "logistic,nb", "--tune", "--budget",
        "0.01",
    )  # fmt: skip
    regression = _bench(capsys, db, "c", "-c", "zeror,ridge", "--position", "x,y")
    assert tuned["run_id"] == 1 and regression["run_id"] == 2

    output = tmp_path / "report.html"
    result = run_cli(capsys, db, "report", "1", "2", "-o", str(output))
    assert result.code == 0, result.err
    report = output.read_text(encoding="utf-8")
    _check_tuning(tables(report.split('<section id="run-2">')[0]), tuned)
    _check_targets(tables(report.split('<section id="run-2">')[1]), regression)
    assert not [t for t in tables(report) if t["key"] == "target" and "logistic" in str(t)]

    settings = Settings(database_url=db, work_dir=tmp_path / "work")
    with TestClient(create_app(settings), base_url="http://localhost") as client:
        page = client.get("/fragments/runs/1/leaderboard")
        assert page.status_code == 200, page.text
        _check_tuning(tables(page.text), tuned)
        assert not [t for t in tables(page.text) if t["key"] == "target"]
        page = client.get("/fragments/runs/2/leaderboard")
        assert page.status_code == 200, page.text
        _check_targets(tables(page.text), regression)
        assert not [t for t in tables(page.text) if t["key"] in ("tuning", "choices")]

    shown = run_cli(capsys, db, "leaderboard", "2")
    assert shown.code == 0, shown.err
    lines = shown.out.splitlines()
    assert any(line.startswith("target x") for line in lines)
    ridge = next(r for r in regression["leaderboard"] if r["classifier"] == "ridge")
    mae = ridge["metrics"]["per_target"]["y"]["mae"]
    below = lines[next(i for i, line in enumerate(lines) if line.startswith("target y")) :]
    assert any("ridge" in line and f"{mae['mean']:.4f} ±{mae['std']:.3f}" in line for line in below)
