"""WEKA Experimenter's InstanceResultListener rows read back as per-fold results.

The reverse of :mod:`benchmark.evaluation.results_arff`: each row of a results file (one
run x fold x scheme) becomes a :class:`~benchmark.results.TaskResult` whose classifier is
the scheme's short class name (``weka.classifiers.trees.RandomForest`` ->
``RandomForest``) and whose metrics are WEKA's measures under touchbench's names.  WEKA
keeps no confusion matrix in these files, so imported results have none.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from touchbench.benchmark.dataset import Dataset
from touchbench.benchmark.errors import DataFormatError
from touchbench.benchmark.evaluation.results_arff import KEY_ATTRIBUTES, RELATION
from touchbench.benchmark.results import TaskKey, TaskResult

#: touchbench's metric name -> (WEKA attribute, factor): the measures WEKA defines as we do.
WEKA_METRICS: dict[str, tuple[str, float]] = {
    "accuracy": ("Percent_correct", 0.01),
    "f1_weighted": ("Weighted_avg_F_measure", 1.0),
    "f1_macro": ("Unweighted_macro_avg_F_measure", 1.0),
    "precision_weighted": ("Weighted_avg_IR_precision", 1.0),
    "recall_weighted": ("Weighted_avg_IR_recall", 1.0),
    "kappa": ("Kappa_statistic", 1.0),
    "roc_auc": ("Weighted_avg_area_under_ROC", 1.0),
    "mean_absolute_error": ("Mean_absolute_error", 1.0),
    "root_mean_squared_error": ("Root_mean_squared_error", 1.0),
    "fit_time": ("Elapsed_Time_training", 1.0),
    "predict_time": ("Elapsed_Time_testing", 1.0),
    "fit_cpu_time": ("UserCPU_Time_training", 1.0),
    "predict_cpu_time": ("UserCPU_Time_testing", 1.0),
    "model_size": ("Serialized_Model_Size", 1.0),
}

#: The columns a results file must have to be imported.
REQUIRED = (
    *KEY_ATTRIBUTES[:5],
    "Number_of_training_instances",
    "Number_of_testing_instances",
    "Weighted_avg_F_measure",
)

#: WEKA appends each filter applied to a data set to its relation name.
_FILTERS = "-weka.filters."
_REMOVE = re.compile(r"^unsupervised\.attribute\.Remove-R([0-9,\-]+)(?:-|$)")


@dataclass(frozen=True)
class Scheme:
    """One configuration of a results file: its short name and what WEKA called it.

    Attributes
    ----------
    classifier : str
        The name the imported run gives it (``RandomForest``; ``RandomForest#2`` for a
        second configuration of the same class).
    scheme : str
        WEKA's class name (``weka.classifiers.trees.RandomForest``).
    options : str
        Its options as WEKA wrote them.
    version : str
        ``Key_Scheme_version_ID``.
    """

    classifier: str
    scheme: str
    options: str
    version: str

    def to_json(self) -> dict[str, str]:
        return {
            "classifier": self.classifier,
            "scheme": self.scheme,
            "options": self.options,
            "version": self.version,
        }


@dataclass(frozen=True)
class ImportedResults:
    """A results file's rows as touchbench results.

    Attributes
    ----------
    key_dataset : str
        ``Key_Dataset``: the relation name of the data WEKA used, with its filters.
    schemes : list of Scheme
        In the order the rows first name them.
    results : list of TaskResult
        One per row, 0-based ``repeat`` (WEKA's ``Key_Run``) and ``fold``.
    n_folds, n_repeats : int
        Distinct folds and runs in the rows.
    n_instances : int
        Training plus test instances of a fold (the size of the data WEKA used).
    """

    key_dataset: str
    schemes: list[Scheme]
    results: list[TaskResult]
    n_folds: int
    n_repeats: int
    n_instances: int

    @property
    def relation(self) -> str:
        """The data set's relation name without WEKA's filters (``Sound_Gestures: -C 2``)."""
        return self.key_dataset.split(_FILTERS, 1)[0]

    def removed_attributes(self) -> list[int] | None:
        """0-based attributes removed by a ``Remove`` filter applied first, if any (WEKA's
        way of keeping one of several targets), else ``None``."""
        parts = self.key_dataset.split(_FILTERS)
        if len(parts) < 2:
            return None
        found = _REMOVE.match(parts[1])
        if found is None:
            return None
        removed: list[int] = []
        for piece in found.group(1).split(","):
            low, _, high = piece.partition("-")
            if not low.isdigit() or (high and not high.isdigit()):
                return None
            removed += range(int(low) - 1, int(high or low))
        return removed


def import_weka_results(dataset: Dataset, *, source: str) -> ImportedResults:
    """Read WEKA Experimenter's InstanceResultListener rows (one data set).

    Parameters
    ----------
    dataset : Dataset
        The results file as read by :func:`benchmark.io.arff.read_arff`.
    source : str
        What messages call the file.

    Returns
    -------
    ImportedResults

    Raises
    ------
    DataFormatError
        Not a results file (relation or columns), no rows, rows on several data sets, a
        run or fold that is not a positive number, a (run, fold, scheme) given twice, or
        a row without a weighted F-measure.
    """
    schema = dataset.schema
    if schema.relation != RELATION:
        raise DataFormatError(
            f"not a WEKA Experimenter results file: the relation is '{schema.relation}', "
            f"not '{RELATION}'",
            source=source,
        )
    names = [a.name for a in schema.attributes]
    for needed in REQUIRED:
        if needed not in names:
            raise DataFormatError(
                "not a WEKA Experimenter results file: no attribute",
                source=source,
                attribute=needed,
            )
    values = dataset.values
    if values.shape[0] == 0:
        raise DataFormatError("the results file has no rows", source=source)

    def column(name: str) -> np.ndarray:
        return values[:, schema.index(name)]

    def labels(name: str) -> tuple[str, ...]:
        attribute = schema.attributes[schema.index(name)]
        return attribute.values

    datasets = sorted({labels("Key_Dataset")[int(i)] for i in _present(column("Key_Dataset"))})
    if len(datasets) != 1:
        raise DataFormatError(
            f"the rows hold results on {len(datasets)} data sets; a run holds one: "
            "split the file by Key_Dataset",
            source=source,
        )
    runs = _numbers(column("Key_Run"), labels("Key_Run"), "Key_Run", source)
    folds = _numbers(column("Key_Fold"), labels("Key_Fold"), "Key_Fold", source)
    schemes = _schemes(dataset, source)
    scheme_of = [schemes[key] for key in _scheme_keys(dataset)]
    n_train = column("Number_of_training_instances")
    n_test = column("Number_of_testing_instances")
    measures = {
        metric: (column(name) * factor if name in names else None)
        for metric, (name, factor) in WEKA_METRICS.items()
    }
    seen: set[TaskKey] = set()
    results = []
    for i in range(values.shape[0]):
        key = TaskKey(scheme_of[i].classifier, runs[i] - 1, folds[i] - 1)
        if key in seen:
            raise DataFormatError(
                f"row {i + 1} of the data repeats {key.classifier} on run {runs[i]}, "
                f"fold {folds[i]}",
                source=source,
            )
        seen.add(key)
        metrics = {
            metric: float(cells[i]) for metric, cells in measures.items() if cells is not None
        }
        if math.isnan(metrics["f1_weighted"]):
            raise DataFormatError(
                f"row {i + 1} of the data has no weighted F-measure",
                source=source,
                attribute="Weighted_avg_F_measure",
            )
        results.append(
            TaskResult(key, "ok", None, metrics, None, _count(n_train[i]), _count(n_test[i]))
        )
    sizes = {r.n_train + r.n_test for r in results}
    return ImportedResults(
        key_dataset=datasets[0],
        schemes=list(dict.fromkeys(scheme_of)),
        results=results,
        n_folds=len(set(folds)),
        n_repeats=len(set(runs)),
        n_instances=max(sizes),
    )


def short_name(scheme: str) -> str:
    """``weka.classifiers.trees.RandomForest`` -> ``RandomForest`` (the paper's names)."""
    return scheme.rsplit(".", 1)[-1] or scheme


def _scheme_keys(dataset: Dataset) -> list[tuple[str, str, str]]:
    """(scheme, options, version) of every row."""
    schema = dataset.schema
    out = []
    columns = [schema.index(name) for name in KEY_ATTRIBUTES[3:]]
    tables = [schema.attributes[c].values for c in columns]
    for row in dataset.values[:, columns]:
        out.append(
            tuple(
                "" if math.isnan(cell) else table[int(cell)]
                for cell, table in zip(row, tables, strict=True)
            )
        )
    return out  # type: ignore[return-value]  # three columns, three strings


def _schemes(dataset: Dataset, source: str) -> dict[tuple[str, str, str], Scheme]:
    """A :class:`Scheme` per distinct (scheme, options, version), named by class."""
    out: dict[tuple[str, str, str], Scheme] = {}
    taken: dict[str, int] = {}
    for key in dict.fromkeys(_scheme_keys(dataset)):
        scheme, options, version = key
        if not scheme:
            raise DataFormatError("a row has no Key_Scheme", source=source)
        base = short_name(scheme)
        taken[base] = taken.get(base, 0) + 1
        name = base if taken[base] == 1 else f"{base}#{taken[base]}"
        out[key] = Scheme(name, scheme, options, version)
    return out


def _numbers(cells: np.ndarray, table: Sequence[str], name: str, source: str) -> list[int]:
    """WEKA's nominal run and fold numbers (``'1'``..) as positive integers."""
    out = []
    for cell in cells:
        text = "" if math.isnan(cell) else table[int(cell)]
        if not (text.isascii() and text.isdigit() and int(text) >= 1):
            raise DataFormatError(
                f"'{text or '?'}' is not a run or fold number (1, 2, ...)",
                source=source,
                attribute=name,
            )
        out.append(int(text))
    return out


def _present(cells: np.ndarray) -> np.ndarray:
    return cells[~np.isnan(cells)]


def _count(value: float) -> int:
    return 0 if math.isnan(value) else int(value)
