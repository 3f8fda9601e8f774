"""What pages and plots show of long lists: the first items and a count of the others, and
plots whose panels and classes stay bounded however many targets and classes there are."""

from __future__ import annotations

import numpy as np

from tests.support.figures import svg_texts
from touchbench.app.reports import bounds
from touchbench.app.reports.plots import (
    class_distribution_figure,
    confusion_figure,
    per_target_figure,
    svg_text,
)
from touchbench.app.schemas.listing import Page
from touchbench.app.web.listing import newest


def test_first_last_and_names_count_what_they_leave_out() -> None:
    shown = bounds.first(range(25), 10)
    assert shown.items == list(range(10)) and shown.more == 15 and shown.total == 25
    assert bounds.first({"a": 1, "b": 2}, 10) == bounds.Shown(["a", "b"], 0)
    pages: list[Page] = []

    def listed(*, page: Page) -> list[int]:
        pages.append(page)
        return list(range(25))[page.offset : page.offset + page.limit]

    latest = newest(25, listed, 10)
    assert latest.items == list(range(15, 25)) and latest.more == 15
    assert pages == [Page(offset=15, limit=10)]
    assert newest(3, lambda *, page: [0, 1, 2][page.offset :], 10) == bounds.Shown([0, 1, 2], 0)
    assert bounds.names([f"y{i}" for i in range(20_000)], 3) == "y0, y1, y2 and 19,997 more"
    assert bounds.names(["a", "b"]) == "a, b"
    assert bounds.of_all(bounds.first(range(800), 6), "targets") == "first 6 of 800 targets"
    assert bounds.of_all(bounds.first(range(6), 6), "targets") == ""
    assert bounds.first_entries({i: i for i in range(9)}, 2) == {0: 0, 1: 1}


def _panels(texts: list[str], suffix: str) -> list[str]:
    return [text for text in texts if text.endswith(suffix)]


def test_class_plot_of_800_targets_with_100_classes_draws_the_first() -> None:
    counts = {f"y{t}": {f"c{k}": k for k in range(100)} for t in range(800)}
    texts = svg_texts(svg_text(class_distribution_figure(counts, title="wide")))
    titles = [text for text in texts if text.startswith("y") and "instances" in text]
    assert titles == [
        f"y{t} (4950 instances; first {bounds.CLASSES} of 100 classes)"
        for t in range(bounds.PANELS)
    ]
    assert f"wide (first {bounds.PANELS} of 800 targets)" in texts
    assert f"c{bounds.CLASSES - 1}" in texts and f"c{bounds.CLASSES}" not in texts


def test_per_target_and_confusion_plots_draw_the_first_targets_and_classes() -> None:
    summary = {"rf": {f"y{t}": (0.5, 0.1) for t in range(300)}}
    texts = svg_texts(svg_text(per_target_figure(summary, metric="accuracy", title="acc")))
    assert [text for text in texts if text.startswith("y")] == [
        f"y{t}" for t in range(bounds.PANELS)
    ]
    assert f"acc (first {bounds.PANELS} of 300 targets)" in texts

    n = 200
    matrices = {f"y{t}": np.eye(n, dtype=np.int64) * 3 for t in range(10)}
    labels = {f"y{t}": [f"c{k}" for k in range(n)] for t in range(10)}
    texts = svg_texts(svg_text(confusion_figure(matrices, labels, title="cm")))
    assert f"cm (first {bounds.PANELS} of 10 targets)" in texts
    assert f"y0, first {bounds.CLASSES} of {n} classes" in texts
    assert f"c{bounds.CLASSES}" not in texts
