"""Published results as runs of their own: a WEKA Experimenter results file imported.

The UC3M authors' ``weka_results_*.arff`` (and any InstanceResultListener file WEKA's
Experimenter writes) become a ``done`` run on the stored data set the results are of, one
result per (run, fold, scheme), so that leaderboards and reports show the paper's
classifiers beside ours (:mod:`app.services.beside`).
"""

from __future__ import annotations

from pathlib import Path

from touchbench.app.errors import FieldError
from touchbench.app.schemas.imported import ImportResultsRequest
from touchbench.app.schemas.run_config import IMPORTED, ImportedScheme, RunConfig
from touchbench.app.services.listing import list_datasets
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import load_schema
from touchbench.app.store.runs import RunInfo, add_finished_run
from touchbench.benchmark.dataset import Schema
from touchbench.benchmark.errors import DataFormatError
from touchbench.benchmark.evaluation.results_import import ImportedResults, import_weka_results
from touchbench.benchmark.io.arff import open_arff


def is_imported(run: RunInfo) -> bool:
    """Whether the run's results were imported rather than computed here."""
    return run.config.imported


def import_results(store: Store, request: ImportResultsRequest) -> RunInfo:
    """Store a WEKA Experimenter results file as a finished multi-class run.

    Parameters
    ----------
    store : Store
    request : ImportResultsRequest
        The file; optionally the run's name, the data set (default: the only stored one
        whose relation is the file's ``Key_Dataset`` without its filters) and the target
        (default: the data set's only target, or the one a leading ``Remove`` filter in
        ``Key_Dataset`` left).

    Returns
    -------
    RunInfo
        Status ``done``; classifiers named by WEKA class (``RandomForest``), their
        options in ``config.schemes``.

    Raises
    ------
    DataFormatError
        Not a readable InstanceResultListener ARFF (with its line), or rows whose folds
        do not add up to the data set's instances.
    FieldError
        ``dataset`` or ``target`` absent and not to be told from the file, or not
        matching it.
    NotFoundError
        No such data set.
    """
    label = request.source_name or str(request.file)
    with open_arff(request.file, source=label) as reader:
        imported = import_weka_results(reader.read(), source=label)
    dataset = request.dataset or _dataset_by_relation(store, imported.relation)
    info, schema, _ = load_schema(store, dataset)
    target = request.target or _target(schema, imported)
    if target not in schema.target_names:
        raise FieldError(
            "target",
            f"'{target}' is not a target of data set '{info.name}' "
            f"(targets: {', '.join(schema.target_names)})",
        )
    if imported.n_instances != info.n_instances:
        raise DataFormatError(
            f"the results' folds hold {imported.n_instances} instances and data set "
            f"'{info.name}' has {info.n_instances}: they are not results on it",
            source=label,
        )
    config = RunConfig(
        origin=IMPORTED,
        name=request.name or f"WEKA {Path(request.source_name or request.file).name}",
        source=Path(request.source_name or request.file).name,
        key_dataset=imported.key_dataset,
        folds=imported.n_folds,
        repeats=imported.n_repeats,
        fold_scheme=f"WEKA Experimenter's {imported.n_folds}-fold (imported)",
        n_tasks=len(imported.results),
        schemes=[ImportedScheme(**scheme.to_json()) for scheme in imported.schemes],
    )
    return add_finished_run(
        store,
        dataset_id=info.id,
        kind="multiclass",
        targets=[target],
        classifiers=[scheme.classifier for scheme in imported.schemes],
        config=config,
        results=imported.results,
    )


def _dataset_by_relation(store: Store, relation: str) -> str:
    """The one stored data set whose relation is ``relation``."""
    named = [d.name for d in list_datasets(store) if d.relation == relation]
    if len(named) == 1:
        return named[0]
    if not named:
        raise FieldError(
            "dataset",
            f"no stored data set has the results' relation '{relation}': "
            "import the data set first, or name the one the results are of",
        )
    raise FieldError(
        "dataset",
        f"{len(named)} stored data sets have the results' relation '{relation}' "
        f"({', '.join(named)}): name the one the results are of",
    )


def _target(schema: Schema, imported: ImportedResults) -> str:
    """The data set's only target, or the one WEKA's leading Remove filter left."""
    targets = list(schema.target_names)
    if len(targets) == 1:
        return targets[0]
    removed = imported.removed_attributes()
    if removed is not None:
        names = [a.name for a in schema.attributes]
        left = [t for t in targets if names.index(t) not in removed]
        if len(left) == 1:
            return left[0]
    raise FieldError(
        "target",
        f"the results file does not say which of the targets ({', '.join(targets)}) "
        "its schemes predicted: name it",
    )
