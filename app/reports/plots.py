"""Plots of results, as matplotlib figures that render to SVG text (web pages, HTML
reports) or PNG bytes.

Every plot function takes plain numbers and labels, never the store, and returns a
:class:`matplotlib.figure.Figure` built without pyplot.  matplotlib's settings are global,
so building and rendering hold one lock while the plots' settings are in force: a web
server's threads drawing at once would otherwise undo each other's settings (text drawn
as paths, lost to the SVG's readers).  :func:`svg_text` renders one with its text kept as text
(``svg.fonttype: none``), so labels stay searchable and parseable and the file small, and
with fixed ids and no date, so the same figure renders to the same bytes.
"""

from __future__ import annotations

import io
import math
import os
import secrets
import textwrap
import threading
from collections.abc import Callable, Mapping, Sequence
from functools import wraps
from pathlib import Path
from typing import Any, ParamSpec

import numpy as np
from matplotlib import rc_context
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from numpy.typing import ArrayLike

from touchbench.app.errors import AppError
from touchbench.app.reports.bounds import CLASSES, DRAWN, PANELS, first, of_all

#: Output formats of :func:`save_figure`, by file suffix.
FORMATS = ("svg", "png")
#: Confusion matrices with more classes than this show colours without numbers.
MAX_ANNOTATED_CLASSES = 15

#: matplotlib settings of every plot, applied while it is built and while it is rendered.
_RC: Any = {
    "svg.fonttype": "none",
    "svg.hashsalt": "touchbench",
    "font.size": 9,
    "axes.titlesize": 10,
    "figure.dpi": 100,
}
_P = ParamSpec("_P")
#: Held while the plots' settings are in force (see the module's docstring).
_SETTINGS = threading.RLock()
_METADATA_SVG = {"Date": None, "Creator": "touchbench"}
_METADATA_PNG = {"Software": "touchbench"}
_LINE = "#333333"
_ACCENT = "#1f77b4"
_MUTED = "#9ecae1"


def _styled(build: Callable[_P, Figure]) -> Callable[_P, Figure]:
    """Build the figure under the plots' matplotlib settings (fonts are set on creation)."""

    @wraps(build)
    def styled(*args: _P.args, **kwargs: _P.kwargs) -> Figure:
        with _SETTINGS, rc_context(_RC):
            return build(*args, **kwargs)

    return styled


@_styled
def cd_diagram(
    average_ranks: Mapping[str, float],
    critical_difference: float,
    groups: Sequence[Sequence[str]],
    *,
    title: str,
) -> Figure:
    """Demšar's critical-difference diagram.

    Parameters
    ----------
    average_ranks : mapping of str to float
        Average rank of each classifier (1 = best).
    critical_difference : float
        Nemenyi's CD, drawn as a bar of that length above the axis.
    groups : sequence of sequence of str
        Classifiers not significantly different from each other; each group is a thick
        bar joining their ranks.
    title : str

    Returns
    -------
    Figure
        Rank axis from 1 (left, best) to k; the better half of the classifiers labelled
        on the left, the others on the right, each label ``"name (rank)"``.
    """
    names = sorted(average_ranks, key=lambda name: (average_ranks[name], name))
    k = len(names)
    if k < 2:
        raise AppError(f"a critical-difference diagram needs at least 2 classifiers, got {k}")
    left_side = names[: (k + 1) // 2]
    right_side = names[(k + 1) // 2 :][::-1]
    rows = max(len(left_side), len(right_side))
    step = 0.32
    group_space = 0.18 * (len(groups) + 1)
    height = 1.3 + group_space * 0.9 + rows * step
    figure = Figure(figsize=(9.0, height), layout=None)
    title_share = 0.45 / height
    ax = figure.add_axes((0.28, 0.0, 0.44, 1.0 - title_share))
    ax.set_axis_off()
    top, bottom = -0.9, group_space + rows * step + 0.1
    ax.set_xlim(0.9, k + 0.1)
    ax.set_ylim(bottom, top)
    figure.suptitle(
        textwrap.fill(title, width=int(figure.get_figwidth() * 13)), y=1.0 - 0.12 / height, va="top"
    )
    # the rank axis
    ax.plot([1, k], [0, 0], color=_LINE, linewidth=1)
    for tick in range(1, k + 1):
        ax.plot([tick, tick], [0, -0.08], color=_LINE, linewidth=1)
        ax.text(tick, -0.12, str(tick), ha="center", va="bottom")
    # the critical difference
    cd_end = 1 + critical_difference
    ax.plot([1, min(cd_end, k)], [-0.55, -0.55], color=_LINE, linewidth=1.5)
    for x in (1, min(cd_end, k)):
        ax.plot([x, x], [-0.6, -0.5], color=_LINE, linewidth=1)
    ax.text(1, -0.62, f"CD = {critical_difference:.3f}", ha="left", va="bottom")
    # groups of classifiers the test does not tell apart
    for g, group in enumerate(groups):
        ranks = [average_ranks[name] for name in group]
        y = 0.14 + 0.18 * g
        ax.plot([min(ranks) - 0.03, max(ranks) + 0.03], [y, y], color=_LINE, linewidth=3)
    # one elbow line and label per classifier
    for side, anchor, align in ((left_side, 0.9, "right"), (right_side, k + 0.1, "left")):
        for i, name in enumerate(side):
            rank = average_ranks[name]
            y = group_space + 0.1 + i * step
            ax.plot([rank, rank, anchor], [0, y, y], color=_LINE, linewidth=0.8)
            ax.text(
                anchor + (-0.05 if align == "right" else 0.05),
                y,
                f"{name} ({rank:.2f})",
                ha=align,
                va="center",
                clip_on=False,
            )
    return figure


@_styled
def fold_strip_plot(
    scores: Mapping[str, ArrayLike],
    *,
    metric: str,
    lower_is_better: bool = False,
    title: str,
) -> Figure:
    """Every fold's score of every classifier, one row per classifier, best on top.

    Parameters
    ----------
    scores : mapping of str to array-like of shape (n_folds,)
        Per-fold scores of each classifier (NaN for a failed fold: left out, and counted
        in the row label).
    metric : str
        The axis label.
    lower_is_better : bool
        The metric's direction, which orders the rows.
    title : str

    Returns
    -------
    Figure
        Dots for folds (spread vertically so that equal scores stay visible), a bar for the
        mean; the best :data:`~app.reports.bounds.DRAWN` classifiers, the title saying so
        when there are more.
    """
    if not scores:
        raise AppError("no classifier to plot")
    columns = {name: np.asarray(values, dtype=np.float64) for name, values in scores.items()}

    def key(name: str) -> tuple[bool, float, str]:
        finite = columns[name][~np.isnan(columns[name])]
        if finite.size == 0:
            return (True, 0.0, name)
        mean = float(finite.mean())
        return (False, mean if lower_is_better else -mean, name)

    best = first(sorted(columns, key=key), DRAWN)
    names = best.items
    if best.more:
        title = f"{title}\n(the best: {of_all(best, 'classifiers')})"
    figure = Figure(figsize=(7.5, 1.1 + 0.3 * len(names)), layout="constrained")
    ax = figure.add_subplot()
    jitter = np.random.default_rng(0)
    labels = []
    for row, name in enumerate(names):
        values = columns[name]
        finite = values[~np.isnan(values)]
        failed = values.size - finite.size
        labels.append(f"{name} ({failed} failed)" if failed else name)
        if finite.size:
            offsets = jitter.uniform(-0.18, 0.18, finite.size)
            ax.scatter(finite, row + offsets, s=14, color=_ACCENT, alpha=0.75, linewidths=0)
            ax.plot([finite.mean()] * 2, [row - 0.3, row + 0.3], color=_LINE, linewidth=1.5)
    ax.set_yticks(range(len(names)), labels)
    ax.set_ylim(len(names) - 0.5, -0.5)
    direction = "lower is better" if lower_is_better else "higher is better"
    ax.set_xlabel(f"{metric} per fold ({direction}; bar: mean)")
    ax.grid(axis="x", color="#dddddd", linewidth=0.6)
    ax.set_axisbelow(True)
    ax.set_title(title, loc="left")
    return figure


@_styled
def confusion_figure(
    matrices: Mapping[str, np.ndarray],
    labels: Mapping[str, Sequence[str]],
    *,
    title: str,
) -> Figure:
    """Confusion matrices normalised per row, one panel per target.

    Parameters
    ----------
    matrices : mapping of str to ndarray of shape (n_classes, n_classes)
        Counts per target (rows true, columns predicted), e.g. summed over folds.
    labels : mapping of str to sequence of str
        The class labels of each target, in code order (the schema's).
    title : str

    Returns
    -------
    Figure
        Cells coloured by the share of the true class predicted as each class; with up to
        :data:`MAX_ANNOTATED_CLASSES` classes each cell also shows the share and the count.
        A class that never occurs shows an empty row.
    """
    if not matrices:
        raise AppError("no confusion matrix to plot")
    shown = first(matrices, PANELS)
    targets = shown.items
    sizes = [min(len(labels[t]), CLASSES) for t in targets]
    side = max(3.2, min(9.0, 0.55 * max(sizes) + 1.6))
    figure = Figure(figsize=(side * len(targets), side + 0.5), layout="constrained")
    axes = figure.subplots(1, len(targets), squeeze=False)[0]
    image = None
    for ax, target in zip(axes, targets, strict=True):
        counts = np.asarray(matrices[target], dtype=np.float64)
        names = list(labels[target])
        if counts.shape != (len(names), len(names)):
            raise AppError(
                f"confusion matrix of '{target}' has shape {counts.shape} for {len(names)} labels"
            )
        totals = counts.sum(axis=1, keepdims=True)  # over every class, shown or not
        shares = np.divide(counts, totals, out=np.full_like(counts, np.nan), where=totals > 0)
        classes = first(names, CLASSES)
        names, n = classes.items, len(classes.items)
        shares, counts = shares[:n, :n], counts[:n, :n]
        image = ax.imshow(shares, cmap="Blues", vmin=0.0, vmax=1.0)
        ax.set_xticks(range(len(names)), names, rotation=45, ha="right", rotation_mode="anchor")
        ax.set_yticks(range(len(names)), names)
        ax.set_xlabel("predicted")
        ax.set_ylabel("true")
        if len(targets) > 1 or classes.more:
            ax.set_title(", ".join(filter(None, [target, of_all(classes, "classes")])))
        if len(names) <= MAX_ANNOTATED_CLASSES:
            _annotate_cells(ax, shares, counts)
    if image is not None:
        figure.colorbar(image, ax=list(axes), shrink=0.8, label="share of the true class")
    _suptitle(figure, title, of_all(shown, "targets"))
    return figure


@_styled
def reliability_diagram(
    curves: Mapping[str, tuple[np.ndarray, np.ndarray, np.ndarray, float]],
    *,
    title: str,
) -> Figure:
    """Reliability diagram: accuracy against mean confidence per bin, one line per
    classifier, the diagonal for perfect calibration, and the share of instances per bin.

    Parameters
    ----------
    curves : mapping of str to (confidence, accuracy, count, ece)
        Per classifier: mean confidence, accuracy and instances of each bin (ndarrays of
        shape (n_bins,), NaN for empty bins) and its expected calibration error.
    title : str
    """
    if not curves:
        raise AppError("no calibration to plot")
    figure = Figure(figsize=(6.4, 5.6), layout="constrained")
    top, bottom = figure.subplots(2, 1, sharex=True, height_ratios=(3, 1))
    top.plot([0, 1], [0, 1], linestyle="--", color=_LINE, linewidth=0.8, label="perfect")
    n_bins = 1
    for name, (confidence, accuracy, count, ece) in curves.items():
        shown = count > 0
        top.plot(confidence[shown], accuracy[shown], marker="o", label=f"{name} (ECE {ece:.3f})")
        n_bins = count.size
        centres = (np.arange(n_bins) + 0.5) / n_bins
        bottom.plot(centres, count / max(count.sum(), 1.0), marker=".", label=name)
    top.set_xlim(0, 1)
    top.set_ylim(0, 1)
    top.set_ylabel("accuracy of the top label")
    top.legend(loc="upper left", fontsize=8)
    bottom.set_xlabel("confidence of the top label")
    bottom.set_ylabel("share")
    _suptitle(figure, title)
    return figure


@_styled
def per_target_figure(
    summary: Mapping[str, Mapping[str, tuple[float, float]]],
    *,
    metric: str,
    title: str,
) -> Figure:
    """A multi-target run's score on each target, one panel per target.

    Parameters
    ----------
    summary : mapping of str to mapping of str to (float, float)
        classifier -> target -> (mean, standard deviation) of ``metric`` over folds
        (NaN standard deviation: no error bar).
    metric : str
    title : str

    Returns
    -------
    Figure
        A dot per classifier at its mean, classifiers in the order given (a
        leaderboard's; the first :data:`~app.reports.bounds.DRAWN`), error bars one
        standard deviation.
    """
    drawn = first(list(summary), DRAWN)
    classifiers = drawn.items
    shown = first(dict.fromkeys(t for by_target in summary.values() for t in by_target), PANELS)
    targets = shown.items
    if not classifiers or not targets:
        raise AppError("no per-target scores to plot")
    figure = Figure(
        figsize=(3.4 * len(targets) + 1.5, 1.2 + 0.28 * len(classifiers)), layout="constrained"
    )
    axes = figure.subplots(1, len(targets), squeeze=False, sharey=True)[0]
    rows = np.arange(len(classifiers))
    for ax, target in zip(axes, targets, strict=True):
        pairs = [summary[c].get(target, (math.nan, math.nan)) for c in classifiers]
        means = np.array([m for m, _ in pairs], dtype=np.float64)
        stds = np.nan_to_num(np.array([s for _, s in pairs], dtype=np.float64))
        ax.errorbar(
            means,
            rows,
            xerr=stds,
            fmt="o",
            color=_ACCENT,
            ecolor=_LINE,
            elinewidth=0.8,
            capsize=2,
            markersize=4,
        )
        ax.set_title(target)
        ax.set_xlabel(metric)
        ax.grid(axis="x", color="#dddddd", linewidth=0.6)
        ax.set_axisbelow(True)
    axes[0].set_yticks(rows, classifiers)
    axes[0].set_ylim(len(classifiers) - 0.5, -0.5)
    left_out = [of_all(shown, "targets"), of_all(drawn, "classifiers")]
    _suptitle(figure, title, "; ".join(text for text in left_out if text))
    return figure


@_styled
def class_distribution_figure(counts: Mapping[str, Mapping[str, int]], *, title: str) -> Figure:
    """How many instances each class has, one panel per target.

    Parameters
    ----------
    counts : mapping of str to mapping of str to int
        target -> label -> number of instances (labels in the schema's order).
    title : str
    """
    shown = first(counts, PANELS)
    targets = shown.items
    if not targets:
        raise AppError("no class counts to plot")
    most = max(min(len(counts[t]), CLASSES) for t in targets)
    figure = Figure(figsize=(3.6 * len(targets) + 0.6, 1.2 + 0.3 * most), layout="constrained")
    axes = figure.subplots(1, len(targets), squeeze=False)[0]
    for ax, target in zip(axes, targets, strict=True):
        total = sum(int(value) for value in counts[target].values())
        classes = first(counts[target], CLASSES)
        names = classes.items
        values = [int(counts[target][name]) for name in names]
        rows = np.arange(len(names))
        ax.barh(rows, values, color=_MUTED, edgecolor=_ACCENT)
        ax.set_yticks(rows, names)
        ax.set_ylim(len(names) - 0.5, -0.5)
        for row, value in zip(rows, values, strict=True):
            share = f" ({value / total:.0%})" if total else ""
            ax.text(value, row, f" {value}{share}", va="center", ha="left")
        ax.set_xlim(0, max([*values, 1]) * 1.35)
        shown_classes = f"; {of_all(classes, 'classes')}" if classes.more else ""
        ax.set_title(f"{target} ({total} instances{shown_classes})")
        ax.set_xlabel("instances")
    _suptitle(figure, title, of_all(shown, "targets"))
    return figure


@_styled
def learning_curve_figure(
    curves: Mapping[str, tuple[np.ndarray, np.ndarray, np.ndarray, float | None]],
    *,
    metric: str,
    lower_is_better: bool = False,
    title: str,
) -> Figure:
    """Learning curves: a classifier's mean score (band: one standard deviation over the
    folds) against the share of each training fold, and a mark where it comes within the
    tolerance of its full score.

    Parameters
    ----------
    curves : mapping of str to (fractions, mean, std, enough)
        Per classifier: ndarrays of shape (n_fractions,) (NaN where nothing scored) and the
        fraction that is enough (``None``: not known yet).
    metric : str
        The axis label.
    lower_is_better : bool
    title : str
    """
    if not curves:
        raise AppError("no learning curve to plot")
    figure = Figure(figsize=(6.4, 4.4), layout="constrained")
    ax = figure.add_subplot()
    for name, (fractions, mean, std, enough) in curves.items():
        shown = ~np.isnan(mean)
        (line,) = ax.plot(fractions[shown], mean[shown], marker="o", label=name)
        spread = shown & ~np.isnan(std)
        ax.fill_between(
            fractions[spread],
            (mean - std)[spread],
            (mean + std)[spread],
            color=line.get_color(),
            alpha=0.15,
            linewidth=0,
        )
        if enough is not None:
            at = np.flatnonzero(np.isclose(fractions, enough))
            if at.size and shown[at[0]]:
                ax.scatter(
                    [enough], [mean[at[0]]], s=90, facecolors="none", edgecolors=line.get_color()
                )
    ax.set_xlim(0, 1.02)
    ax.set_xlabel("share of each training fold (circled: within tolerance of the full score)")
    direction = "lower is better" if lower_is_better else "higher is better"
    ax.set_ylabel(f"{metric} ({direction})")
    ax.grid(color="#dddddd", linewidth=0.6)
    ax.set_axisbelow(True)
    ax.legend(loc="lower right" if not lower_is_better else "upper right", fontsize=8)
    _suptitle(figure, title)
    return figure


@_styled
def change_bars(
    changes: Mapping[str, float | None], *, marked: Sequence[str], xlabel: str, title: str
) -> Figure:
    """Horizontal bars of signed changes (an ablation's score without each group less the
    full set's, a feature's drop when shuffled), one per label, in the given order.

    Parameters
    ----------
    changes : mapping of str to float or None
        label -> change (``None``: not scored, drawn as an empty row).
    marked : sequence of str
        Labels whose change is significant, drawn dark.
    xlabel, title : str
    """
    shown = first(changes, DRAWN)
    labels = shown.items
    if not labels:
        raise AppError("no change to plot")
    values = np.array([np.nan if changes[k] is None else changes[k] for k in labels], dtype=float)
    figure = Figure(figsize=(7.4, 1.2 + 0.28 * len(labels)), layout="constrained")
    ax = figure.add_subplot()
    rows = np.arange(len(labels))
    strong = set(marked)
    colours = [_ACCENT if label in strong else _MUTED for label in labels]
    ax.barh(rows, np.nan_to_num(values), color=colours, edgecolor=_ACCENT)
    ax.set_yticks(rows, labels)
    ax.set_ylim(len(labels) - 0.5, -0.5)
    ax.axvline(0, color=_LINE, linewidth=0.8)
    for row, value in enumerate(values.tolist()):
        text = "not scored" if np.isnan(value) else f" {value:+.3f} "
        ax.text(
            0 if np.isnan(value) else value,
            row,
            text,
            va="center",
            ha="left" if np.isnan(value) or value >= 0 else "right",
        )
    finite = values[~np.isnan(values)]
    reach = float(np.max(np.abs(finite))) if finite.size else 1.0
    ax.set_xlim(-reach * 1.6 - 1e-9, reach * 1.6 + 1e-9)
    ax.set_xlabel(xlabel + " (dark: significant, p <= 0.05)")
    ax.grid(axis="x", color="#dddddd", linewidth=0.6)
    ax.set_axisbelow(True)
    _suptitle(figure, title, of_all(shown, "bars") if shown.more else "")
    return figure


def _suptitle(figure: Figure, title: str, shown: str = "") -> None:
    """A figure title wrapped to the figure's width (about 13 characters an inch at 9 pt),
    saying what is ``shown`` of all there is ("first 6 of 800 targets") when not empty."""
    width = int(figure.get_figwidth() * 13)
    figure.suptitle(textwrap.fill(f"{title} ({shown})" if shown else title, width=max(width, 20)))


def svg_text(figure: Figure, *, inline: bool = False) -> str:
    """The figure as SVG text.

    Parameters
    ----------
    figure : Figure
    inline : bool
        Drop the XML declaration and DOCTYPE, for an ``<svg>`` element inside HTML.
    """
    buffer = io.StringIO()
    with _SETTINGS, rc_context(_RC):
        figure.savefig(buffer, format="svg", metadata=_METADATA_SVG)
    text = buffer.getvalue()
    if inline:
        text = text[text.index("<svg") :]
    return text


def png_bytes(figure: Figure, *, dpi: int = 150) -> bytes:
    """The figure as PNG."""
    buffer = io.BytesIO()
    with _SETTINGS, rc_context(_RC):
        figure.savefig(buffer, format="png", dpi=dpi, metadata=_METADATA_PNG)
    return buffer.getvalue()


def figure_format(path: Path) -> str:
    """``"svg"`` or ``"png"`` from the file's suffix; anything else is refused."""
    suffix = path.suffix.lower().lstrip(".")
    if suffix not in FORMATS:
        raise AppError(
            f"{path}: unknown plot format '{path.suffix or '(none)'}' (use a .svg or .png file)"
        )
    return suffix


def save_figure(figure: Figure, path: Path) -> None:
    """Write the figure to ``path`` (SVG or PNG by suffix) all at once: a temporary file
    in the same folder is renamed over it, so nothing half-written is ever left."""
    data = svg_text(figure).encode() if figure_format(path) == "svg" else png_bytes(figure)
    write_atomically(path, data)


def write_atomically(path: Path, data: bytes) -> None:
    """Replace ``path`` with ``data`` by renaming a finished temporary file over it."""
    folder = path.resolve().parent
    if not folder.is_dir():
        raise AppError(f"{path}: no such folder '{folder}'")
    temporary = folder / f".{path.name}.{secrets.token_hex(6)}.tmp"
    try:
        with open(temporary, "xb") as out:  # open(), unlike mkstemp, honours the umask
            out.write(data)
        os.replace(temporary, path)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise


def _annotate_cells(ax: Axes, shares: np.ndarray, counts: np.ndarray) -> None:
    for (row, column), share in np.ndenumerate(shares):
        if math.isnan(share):
            continue
        colour = "white" if share > 0.6 else _LINE
        ax.text(
            column,
            row,
            f"{share:.2f}\n{int(counts[row, column])}",
            ha="center",
            va="center",
            color=colour,
            fontsize=7,
        )
