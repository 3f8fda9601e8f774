"""`touchbench plot` and `touchbench report` on real benchmark runs (small synthetic data),
on SQLite and PostgreSQL."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from html.parser import HTMLParser
from pathlib import Path

import pytest

from tests.support.cli_runner import run_cli
from tests.support.figures import FETCHES, svg_texts
from tests.support.synthetic import touch_arff
from touchbench.benchmark.evaluation.statistics import nemenyi_critical_difference

CLASSIFIERS = "zeror,nb,j48"


class _Report(HTMLParser):
    """What a report holds: headings, table cells, inline SVGs, tags fetching things."""

    def __init__(self) -> None:
        super().__init__()
        self.headings: list[str] = []
        self.cells: list[str] = []
        self.tags: set[str] = set()
        self._heading = False
        self._cell = False

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.tags.add(tag)
        self._heading = tag in ("h1", "h2", "h3")
        self._cell = tag in ("td", "th")
        if self._heading:
            self.headings.append("")
        if self._cell:
            self.cells.append("")

    def handle_endtag(self, tag: str) -> None:
        if tag in ("h1", "h2", "h3"):
            self._heading = False
        if tag in ("td", "th"):
            self._cell = False

    def handle_data(self, data: str) -> None:
        if self._heading:
            self.headings[-1] += data
        if self._cell:
            self.cells[-1] += data.strip()


def benched(capsys: pytest.CaptureFixture[str], db: str, tmp_path: Path) -> None:
    """Runs 1 and 2: two multi-class data sets; run 3: a multi-target one."""
    for name, seed, place in (("first", 0, False), ("second", 1, False), ("both", 2, True)):
        path = touch_arff(tmp_path / f"{name}.arff", n=60, seed=seed, with_place=place)
        assert run_cli(capsys, db, "import", str(path), "--name", name).code == 0
    for name in ("first", "second"):
        result = run_cli(capsys, db, "bench", name, "-c", CLASSIFIERS, "-k", "3", "--json")
        assert result.code == 0, result.err
    result = run_cli(capsys, db, "bench", "both", "-c", "cc:nb,bcc:j48", "-k", "3", "--json")
    assert result.code == 0, result.err


def test_plots_and_report_of_real_runs(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    benched(capsys, store_url, tmp_path)

    def plot(*args: str) -> Path:
        output = tmp_path / args[-1]
        result = run_cli(capsys, store_url, "plot", *args[:-1], "-o", str(output))
        assert result.code == 0, result.err
        assert result.out == ""
        return output

    cd = svg_texts(plot("1", "--kind", "cd", "cd.svg").read_text())
    assert "3 folds as blocks" in " ".join(cd)
    assert f"CD = {nemenyi_critical_difference(3, 3):.3f}" in cd  # 3 classifiers, 3 folds
    assert {t.split(" (")[0] for t in cd if t.endswith(")") and "(" in t} >= {"zeror", "nb", "j48"}
    folds = svg_texts(plot("2", "--kind", "folds", "folds.svg").read_text())
    assert any("f1_weighted per fold" in t for t in folds)
    assert folds.index("zeror") > max(folds.index("nb"), folds.index("j48"))  # worst last
    confusion = svg_texts(plot("1", "--kind", "confusion", "-c", "j48", "c.svg").read_text())
    assert {"tap", "slap", "stroke", "predicted", "true"} <= set(confusion)
    assert "j48, summed over 3 folds" in " ".join(confusion)  # titles may wrap
    multi = svg_texts(plot("3", "--kind", "confusion", "m.svg").read_text())
    assert {"gesture", "place", "head", "arm", "tap"} <= set(multi)
    targets = svg_texts(plot("3", "--kind", "targets", "t.svg").read_text())
    assert {"gesture", "place", "cc:nb", "bcc:j48"} <= set(targets)
    classes = svg_texts(plot("3", "--kind", "classes", "k.svg").read_text())
    assert "gesture (60 instances)" in classes and "place (60 instances)" in classes
    assert "20 (33%)" in classes and "30 (50%)" in classes
    assert plot("1", "--kind", "folds", "f.png").read_bytes().startswith(b"\x89PNG")

    for args, message in [
        (["plot", "3", "--kind", "cd", "--metric", "kappa", "-o", "x.svg"], "no 'kappa' scores"),
        (["plot", "1", "--kind", "targets", "-o", "x.svg"], "run 1 is multi-class"),
        (["plot", "1", "--kind", "confusion", "-c", "rf", "-o", "x.svg"], "no classifier 'rf'"),
        (["plot", "1", "--kind", "pie", "-o", "x.svg"], "'pie' is not one of"),
        (["plot", "1", "--kind", "cd", "-o", "x.jpg"], "unknown plot format '.jpg'"),
        (["plot", "7", "-o", "x.svg"], "no run '7'"),
        (["report", "1", "-o", "x.pdf"], "must end in .html"),
        (["report", "1", "--confusions", "-1", "-o", "x.html"], "--confusions"),
    ]:
        result = run_cli(capsys, store_url, *args[:-1], str(tmp_path / args[-1]))
        assert result.code == 2, (args, result.err)
        assert message in result.err, result.err
        assert len(result.err.strip().splitlines()) == 1
    assert not list(tmp_path.glob("x.*"))

    output = tmp_path / "report.html"
    result = run_cli(
        capsys, store_url, "report", "1", "2", "3", "--confusions", "2", "-o", str(output)
    )
    assert result.code == 0, result.err
    assert "wrote" in result.err and result.out == ""
    html = output.read_text(encoding="utf-8")
    parsed = _Report()
    parsed.feed(html)
    # self-contained: nothing to fetch, no script, every plot inline
    assert not FETCHES.search(html)
    assert not {"script", "link", "img", "iframe"} & parsed.tags
    headings = [h.strip() for h in parsed.headings]
    assert "run 1: first (gesture)" in headings and "run 3: both (gesture, place)" in headings
    # runs 1 and 2 are multi-class, run 3 multi-target: no comparison across all three
    assert "No comparison across the runs" in html and "mix multi-class and multi-target" in html
    assert {"Leaderboard", "Plots", "Confusion matrices", "Software"} <= set(headings)
    assert {"(base)", "zeror", "nb", "j48", "cc:nb", "bcc:j48", "scikit-learn"} <= set(parsed.cells)
    assert "Not drawn" not in html
    svgs = re.findall(r"<svg.*?</svg>", html, flags=re.S)
    for svg in svgs:
        ET.fromstring(svg)  # each inline SVG is well-formed
    texts = [t for svg in svgs for t in svg_texts(svg)]
    joined = " ".join(texts)
    assert "nb, summed over 3 folds" in joined
    assert "instances per class" in joined
    assert "accuracy per target" in joined

    pair = tmp_path / "pair.html"
    result = run_cli(capsys, store_url, "report", "1", "2", "--confusions", "1", "-o", str(pair))
    assert result.code == 0, result.err
    html = pair.read_text(encoding="utf-8")
    assert "Comparison across 2 data sets" in html
    assert "Friedman: χ²(2)" in html
    assert html.count("Confusion matrix of") == 2  # one per run
