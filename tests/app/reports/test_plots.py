"""Plots: every kind is drawn without error, its SVG keeps labels as text, and files are
written whole."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from tests.support.figures import FETCHES, svg_texts
from touchbench.app.errors import AppError
from touchbench.app.reports.plots import (
    cd_diagram,
    class_distribution_figure,
    confusion_figure,
    fold_strip_plot,
    per_target_figure,
    png_bytes,
    save_figure,
    svg_text,
)

SVG = "{http://www.w3.org/2000/svg}"


def test_cd_diagram_labels_ranks_and_cd() -> None:
    ranks = {"C4.5": 3.143, "C4.5+m": 2.0, "C4.5+cf": 2.893, "C4.5+m+cf": 1.964}
    figure = cd_diagram(
        ranks, 1.25, [("C4.5+m+cf", "C4.5+m", "C4.5+cf", "C4.5")], title="AUC over 14 data sets"
    )
    texts = svg_texts(svg_text(figure))
    assert "AUC over 14 data sets" in texts
    assert "CD = 1.250" in texts
    for name, rank in ranks.items():
        assert f"{name} ({rank:.2f})" in texts
    assert {"1", "2", "3", "4"} <= set(texts)  # the rank axis


def test_fold_strip_plot_orders_best_first_and_counts_failures() -> None:
    scores = {
        "j48": [0.70, 0.72, float("nan")],
        "rf": [0.90, 0.88, 0.91],
        "zeror": [0.33, 0.33, 0.34],
    }
    texts = svg_texts(svg_text(fold_strip_plot(scores, metric="f1_weighted", title="run 1")))
    labels = [t for t in texts if t in ("rf", "j48 (1 failed)", "zeror")]
    assert labels == ["rf", "j48 (1 failed)", "zeror"]
    assert any("f1_weighted per fold" in t and "higher is better" in t for t in texts)
    losses = svg_texts(
        svg_text(fold_strip_plot(scores, metric="log_loss", lower_is_better=True, title="t"))
    )
    assert [t for t in losses if t in ("rf", "j48 (1 failed)", "zeror")] == [
        "zeror",
        "j48 (1 failed)",
        "rf",
    ]


def test_confusion_matrix_is_normalised_per_row_with_schema_labels() -> None:
    matrix = np.array([[8, 2, 0], [1, 9, 0], [0, 0, 0]])
    figure = confusion_figure(
        {"gesture": matrix}, {"gesture": ["tap", "slap", "stroke"]}, title="rf on mini"
    )
    texts = svg_texts(svg_text(figure))
    assert {"tap", "slap", "stroke", "predicted", "true", "rf on mini"} <= set(texts)
    # each cell: its share of the true class over its count; the empty class has no cells
    # (matplotlib writes the two lines of a cell as two text elements)
    cells = [
        (share, texts[i + 1])
        for i, share in enumerate(texts[:-1])
        if re.fullmatch(r"[01]\.\d\d", share)
    ]
    assert cells == [
        ("0.80", "8"),
        ("0.20", "2"),
        ("0.00", "0"),
        ("0.10", "1"),
        ("0.90", "9"),
        ("0.00", "0"),
    ]


def test_confusion_per_target_panels_and_shape_check() -> None:
    figure = confusion_figure(
        {"gesture": np.eye(3, dtype=int) * 5, "place": np.array([[4, 1], [2, 3]])},
        {"gesture": ["tap", "slap", "stroke"], "place": ["head", "arm"]},
        title="bcc:rf",
    )
    texts = svg_texts(svg_text(figure))
    assert {"gesture", "place", "head", "arm", "tap"} <= set(texts)
    with pytest.raises(AppError, match=r"'place' has shape \(2, 2\) for 3 labels"):
        confusion_figure({"place": np.eye(2)}, {"place": ["a", "b", "c"]}, title="x")


def test_per_target_and_class_distribution() -> None:
    summary = {
        "bcc:rf": {"gesture": (0.9, 0.02), "place": (0.8, 0.03)},
        "cc:j48": {"gesture": (0.85, 0.03), "place": (0.82, float("nan"))},
    }
    texts = svg_texts(svg_text(per_target_figure(summary, metric="accuracy", title="run 3")))
    assert {"gesture", "place", "bcc:rf", "cc:j48", "run 3", "accuracy"} <= set(texts)
    counts = {"gesture": {"tap": 30, "slap": 30, "stroke": 29}, "place": {"head": 45, "arm": 44}}
    texts = svg_texts(svg_text(class_distribution_figure(counts, title="mini")))
    assert {"gesture (89 instances)", "place (89 instances)", "tap", "arm"} <= set(texts)
    assert "30 (34%)" in texts and "44 (49%)" in texts


def test_svg_is_reproducible_inline_and_text_stays_text() -> None:
    def draw() -> str:
        return svg_text(
            fold_strip_plot({"rf": [0.9, 0.8], "nb": [0.7, 0.6]}, metric="kappa", title="t")
        )

    first = draw()
    assert first == draw()  # no date, fixed ids
    assert first.startswith("<?xml")
    assert "<text" in first and "font-family" in first  # not glyph outlines
    inline = svg_text(fold_strip_plot({"rf": [0.9, 0.8]}, metric="kappa", title="t"), inline=True)
    assert inline.startswith("<svg") and "<!DOCTYPE" not in inline
    assert not FETCHES.search(inline)  # namespaces name URIs; nothing is fetched


def test_png_and_files(tmp_path: Path) -> None:
    figure = cd_diagram({"a": 1.2, "b": 1.8}, 0.5, [], title="two")
    assert png_bytes(figure).startswith(b"\x89PNG\r\n\x1a\n")
    save_figure(figure, tmp_path / "cd.svg")
    save_figure(figure, tmp_path / "cd.PNG")
    assert (tmp_path / "cd.svg").read_text().lstrip().startswith("<?xml")
    assert (tmp_path / "cd.PNG").read_bytes()[:4] == b"\x89PNG"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cd.PNG", "cd.svg"]  # no leftovers
    with pytest.raises(AppError, match=r"cd.pdf: unknown plot format '.pdf'"):
        save_figure(figure, tmp_path / "cd.pdf")
    with pytest.raises(AppError, match="no such folder"):
        save_figure(figure, tmp_path / "missing" / "cd.svg")
    with pytest.raises(AppError, match="at least 2 classifiers"):
        cd_diagram({"a": 1.0}, 0.5, [], title="one")
