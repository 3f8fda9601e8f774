"""Per-fold results in WEKA's InstanceResultListener format, for WEKA's Experimenter.

The attributes are those of the files WEKA's Experimenter writes (see
``uc3m-touch/*/weka_results_*.arff``), with the same names, types and order, up to
``Summary``; WEKA's scheme-specific ``measure*`` columns are left out.  Values we do not
compute (entropy-based scores, relative errors, areas under PR curves...) are missing.
The class-specific columns (``True_positive_rate``, ``IR_precision``...) describe the first
class, as WEKA's do by default.  Only successful tasks of multi-class runs are exported.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from datetime import datetime
from importlib import metadata
from typing import Any, Protocol

import numpy as np

from touchbench.benchmark.dataset import Attribute, Dataset, Schema
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.results import TaskResult

RELATION = "InstanceResultListener"


class SchemeSpec(Protocol):
    """What the results file says of a classifier (a catalogue entry's spec has it)."""

    @property
    def weka_name(self) -> str | None: ...

    @property
    def weka_options(self) -> str: ...

    @property
    def params(self) -> Mapping[str, Any]: ...


#: Nominal key attributes, in WEKA's order.
KEY_ATTRIBUTES = (
    "Key_Dataset",
    "Key_Run",
    "Key_Fold",
    "Key_Scheme",
    "Key_Scheme_options",
    "Key_Scheme_version_ID",
)

#: Numeric result attributes, in WEKA's order (``Summary``, a string, follows them).
RESULT_ATTRIBUTES = (
    "Date_time",
    "Number_of_training_instances",
    "Number_of_testing_instances",
    "Number_correct",
    "Number_incorrect",
    "Number_unclassified",
    "Percent_correct",
    "Percent_incorrect",
    "Percent_unclassified",
    "Kappa_statistic",
    "Mean_absolute_error",
    "Root_mean_squared_error",
    "Relative_absolute_error",
    "Root_relative_squared_error",
    "SF_prior_entropy",
    "SF_scheme_entropy",
    "SF_entropy_gain",
    "SF_mean_prior_entropy",
    "SF_mean_scheme_entropy",
    "SF_mean_entropy_gain",
    "KB_information",
    "KB_mean_information",
    "KB_relative_information",
    "True_positive_rate",
    "Num_true_positives",
    "False_positive_rate",
    "Num_false_positives",
    "True_negative_rate",
    "Num_true_negatives",
    "False_negative_rate",
    "Num_false_negatives",
    "IR_precision",
    "IR_recall",
    "F_measure",
    "Matthews_correlation",
    "Area_under_ROC",
    "Area_under_PRC",
    "Weighted_avg_true_positive_rate",
    "Weighted_avg_false_positive_rate",
    "Weighted_avg_true_negative_rate",
    "Weighted_avg_false_negative_rate",
    "Weighted_avg_IR_precision",
    "Weighted_avg_IR_recall",
    "Weighted_avg_F_measure",
    "Weighted_avg_matthews_correlation",
    "Weighted_avg_area_under_ROC",
    "Weighted_avg_area_under_PRC",
    "Unweighted_macro_avg_F_measure",
    "Unweighted_micro_avg_F_measure",
    "Elapsed_Time_training",
    "Elapsed_Time_testing",
    "UserCPU_Time_training",
    "UserCPU_Time_testing",
    "UserCPU_Time_millis_training",
    "UserCPU_Time_millis_testing",
    "Serialized_Model_Size",
    "Serialized_Train_Set_Size",
    "Serialized_Test_Set_Size",
    "Coverage_of_Test_Cases_By_Regions",
    "Size_of_Predicted_Regions",
)


def results_to_dataset(
    results: Sequence[TaskResult],
    *,
    dataset_name: str,
    specs: Mapping[str, SchemeSpec],
    timestamp: datetime | None = None,
    scheme_names: str = "weka",
) -> Dataset:
    """WEKA's InstanceResultListener rows, one per successful (run, fold, scheme).

    Parameters
    ----------
    results : sequence of TaskResult
        Results of a multi-class run (failed tasks are skipped).
    dataset_name : str
        ``Key_Dataset`` (WEKA writes the relation name).
    specs : mapping of str to SchemeSpec
        The specs of the run's classifiers by id (the catalogue's, and those of
        configurations made for the run); a classifier without one is written by its id.
    timestamp : datetime, optional
        ``Date_time`` of every row (WEKA's ``yyyymmdd.HHMM`` number); default now.
    scheme_names : {"weka", "id"}
        ``"weka"``: a configuration that reproduces a WEKA command (its
        ``weka_command``) is written as WEKA writes it, ``Key_Scheme`` the class and
        ``Key_Scheme_options`` the options, so that WEKA's Experimenter and
        :func:`benchmark.catalogue.parse_weka_command` read it back; any other is
        ``touchbench.<id>`` with options ``-id <id>`` and its parameters.  ``"id"``: every
        configuration as ``touchbench.<id>``.

    Returns
    -------
    Dataset
        Relation ``InstanceResultListener``; write it with
        :func:`benchmark.io.arff.write_arff`.

    Raises
    ------
    ConfigurationError
        Multi-target results, or an unknown scheme-name style.
    """
    if scheme_names not in ("weka", "id"):
        raise ConfigurationError(f"scheme_names must be 'weka' or 'id', got '{scheme_names}'")
    ok = [r for r in results if r.ok]
    if any(_is_multitarget(r) for r in ok):
        raise ConfigurationError(
            "WEKA's results format holds multi-class runs only; this run has several targets"
        )
    ok.sort(key=lambda r: (r.key.repeat, r.key.fold, r.key.classifier))
    version = _version()
    schemes = {
        c: _scheme(c, specs.get(c), scheme_names)
        for c in dict.fromkeys(r.key.classifier for r in ok)
    }
    labels = {
        "Key_Dataset": [dataset_name],
        "Key_Run": [str(i + 1) for i in range(max((r.key.repeat for r in ok), default=0) + 1)],
        "Key_Fold": [str(i + 1) for i in range(max((r.key.fold for r in ok), default=0) + 1)],
        "Key_Scheme": list(dict.fromkeys(name for name, _ in schemes.values())),
        "Key_Scheme_options": list(dict.fromkeys(options for _, options in schemes.values())),
        "Key_Scheme_version_ID": [version],
    }
    attributes = [Attribute(name, "nominal", tuple(labels[name])) for name in KEY_ATTRIBUTES]
    attributes += [Attribute(name, "numeric", (), "numeric") for name in RESULT_ATTRIBUTES]
    attributes.append(Attribute("Summary", "string", (), "string"))
    date_time = _weka_date(timestamp or datetime.now())
    rows = []
    for result in ok:
        scheme, options = schemes[result.key.classifier]
        keys = [
            0.0,
            float(result.key.repeat),
            float(result.key.fold),
            float(labels["Key_Scheme"].index(scheme)),
            float(labels["Key_Scheme_options"].index(options)),
            0.0,
        ]
        measures = weka_measures(result)
        measures["Date_time"] = date_time
        rows.append(
            keys + [measures.get(name, math.nan) for name in RESULT_ATTRIBUTES] + [math.nan]
        )
    schema = Schema(RELATION, tuple(attributes), (len(attributes) - 1,))
    values = np.array(rows, dtype=np.float64).reshape(len(rows), len(attributes))
    return Dataset(schema, values, name=RELATION)


def weka_measures(result: TaskResult) -> dict[str, float]:
    """WEKA's evaluation measures of one multi-class fold (those we can compute).

    Parameters
    ----------
    result : TaskResult
        A successful multi-class result with its confusion matrix.

    Returns
    -------
    dict of str to float
        Keyed by WEKA attribute name.
    """
    c = np.asarray(result.confusion, dtype=np.float64)
    n = c.sum()
    support = c.sum(axis=1)
    predicted = c.sum(axis=0)
    tp = np.diag(c)
    fn = support - tp
    fp = predicted - tp
    tn = n - tp - fn - fp
    tpr = _div(tp, tp + fn)
    fpr = _div(fp, fp + tn)
    tnr = _div(tn, fp + tn)
    fnr = _div(fn, tp + fn)
    precision = _div(tp, tp + fp)
    f = _div(2 * precision * tpr, precision + tpr)
    mcc = _div(tp * tn - fp * fn, np.sqrt((tp + fp) * (tp + fn) * (tn + fp) * (tn + fn)))
    weights = support / n
    correct = float(tp.sum())
    metrics = result.metrics
    out = {
        "Number_of_training_instances": float(result.n_train),
        "Number_of_testing_instances": float(n),
        "Number_correct": correct,
        "Number_incorrect": n - correct,
        "Number_unclassified": 0.0,
        "Percent_correct": 100.0 * correct / n,
        "Percent_incorrect": 100.0 * (n - correct) / n,
        "Percent_unclassified": 0.0,
        "Kappa_statistic": metrics.get("kappa", math.nan),
        "Mean_absolute_error": metrics.get("mean_absolute_error", math.nan),
        "Root_mean_squared_error": metrics.get("root_mean_squared_error", math.nan),
        "True_positive_rate": tpr[0],
        "Num_true_positives": tp[0],
        "False_positive_rate": fpr[0],
        "Num_false_positives": fp[0],
        "True_negative_rate": tnr[0],
        "Num_true_negatives": tn[0],
        "False_negative_rate": fnr[0],
        "Num_false_negatives": fn[0],
        "IR_precision": precision[0],
        "IR_recall": tpr[0],
        "F_measure": f[0],
        "Matthews_correlation": mcc[0],
        "Weighted_avg_true_positive_rate": weights @ tpr,
        "Weighted_avg_false_positive_rate": weights @ fpr,
        "Weighted_avg_true_negative_rate": weights @ tnr,
        "Weighted_avg_false_negative_rate": weights @ fnr,
        "Weighted_avg_IR_precision": weights @ precision,
        "Weighted_avg_IR_recall": weights @ tpr,
        "Weighted_avg_F_measure": weights @ f,
        "Weighted_avg_matthews_correlation": weights @ mcc,
        "Weighted_avg_area_under_ROC": metrics.get("roc_auc", math.nan),
        "Unweighted_macro_avg_F_measure": float(f.mean()),
        "Unweighted_micro_avg_F_measure": correct / n,
        "Elapsed_Time_training": metrics.get("fit_time", math.nan),
        "Elapsed_Time_testing": metrics.get("predict_time", math.nan),
        "UserCPU_Time_training": metrics.get("fit_cpu_time", math.nan),
        "UserCPU_Time_testing": metrics.get("predict_cpu_time", math.nan),
        "UserCPU_Time_millis_training": 1000.0 * metrics.get("fit_cpu_time", math.nan),
        "UserCPU_Time_millis_testing": 1000.0 * metrics.get("predict_cpu_time", math.nan),
        "Serialized_Model_Size": metrics.get("model_size", math.nan),
    }
    return {name: float(value) for name, value in out.items()}


def _scheme(classifier: str, spec: SchemeSpec | None, style: str) -> tuple[str, str]:
    """``Key_Scheme`` and ``Key_Scheme_options`` of a classifier."""
    if style == "weka" and spec is not None and spec.weka_name:
        return spec.weka_name, spec.weka_options
    name = f"touchbench.{classifier}"
    options = [f"-id {classifier}"]
    if spec is not None:
        options += [f"-{key} {_option_text(value)}" for key, value in spec.params.items()]
    return name, " ".join(options)


def _option_text(value: Any) -> str:
    if isinstance(value, tuple | list):
        return ",".join(str(v) for v in value)
    return str(value)


def _is_multitarget(result: TaskResult) -> bool:
    confusion = result.confusion or [[0]]
    return bool(confusion[0]) and isinstance(confusion[0][0], list)


def _weka_date(moment: datetime) -> float:
    """WEKA's ``Date_time``: ``yyyymmdd.HHMM`` as a number (20170922.0948)."""
    return float(f"{moment:%Y%m%d}.{moment:%H%M}")


def _version() -> str:
    try:
        return f"touchbench-{metadata.version('touchbench')}"
    except metadata.PackageNotFoundError:
        return "touchbench"


def _div(numerator: np.ndarray, denominator: np.ndarray) -> np.ndarray:
    return np.divide(
        numerator,
        denominator,
        out=np.zeros_like(numerator, dtype=np.float64),
        where=denominator > 0,
    )
