"""The metric a run is ranked by: each kind of run's default, and the metrics a kind takes."""

from __future__ import annotations

# Imports inside functions: start-up time: the metrics (scikit-learn) load when a metric
# is first checked.
from touchbench.app.store.runs import RunInfo
from touchbench.benchmark.errors import ConfigurationError

#: Metric a leaderboard is ranked by unless asked otherwise, per kind of run.
DEFAULT_METRIC = {"multiclass": "f1_weighted", "multitarget": "hamming_score", "regression": "mae"}


def run_metric(run: RunInfo) -> str:
    """The metric a run ranks by: the one it was asked, else its kind's."""
    return run.config.metric or DEFAULT_METRIC.get(run.kind, "f1_weighted")


def check_metric(kind: str, metric: str, *, position: bool, run_id: int | None = None) -> None:
    """Refuse a regression metric for a classification and a classification metric for a
    regression (costs such as ``fit_time`` rank either), and the Euclidean error without a
    position.

    Raises
    ------
    ConfigurationError
        One line naming the metric, the kind of run and the metrics it has.
    """
    from touchbench.benchmark.evaluation.metrics import COST_METRICS, REGRESSION_METRICS

    run = f"run {run_id}" if run_id is not None else "this run"
    if metric in COST_METRICS:
        return
    if kind == "regression" and metric not in REGRESSION_METRICS:
        raise ConfigurationError(
            f"'{metric}' is not a regression metric and {run} is a regression (numeric "
            f"targets): rank by {', '.join(REGRESSION_METRICS[:3])} or a cost"
        )
    if kind != "regression" and metric in REGRESSION_METRICS:
        raise ConfigurationError(
            f"'{metric}' is a regression metric and {run} classifies nominal targets "
            f"({kind}): rank by {DEFAULT_METRIC.get(kind, 'f1_weighted')} or another "
            "classification metric"
        )
    if metric == "euclidean_error" and not position:
        raise ConfigurationError(
            f"'euclidean_error' needs coordinates: {run} has no position (2 or 3 numeric "
            "targets that are coordinates)"
        )
