"""A run's per-fold results as WEKA Experimenter's InstanceResultListener ARFF."""

from __future__ import annotations

from typing import TextIO

from app.services.tuning import run_specs
from app.store.database import Store
from app.store.runs import RunInfo, load_results
from benchmark.catalogue import CATALOGUE
from benchmark.errors import ConfigurationError
from benchmark.evaluation.results_arff import results_to_dataset
from benchmark.io.arff import write_arff


def write_results_arff(store: Store, run: RunInfo, stream: TextIO) -> None:
    """Write every successful fold of a multi-class run, one row per (run, fold, scheme)."""
    if run.kind != "multiclass":
        what = "a regression" if run.kind == "regression" else "multi-target"
        raise ConfigurationError(
            f"run {run.id} is {what}; WEKA's results format holds multi-class runs "
            "(the csv and json formats hold every kind)"
        )
    results = load_results(store, run.id)
    name = f"{run.dataset_name}: {', '.join(run.targets)}"
    specs = {**CATALOGUE, **run_specs(run.config, run.classifiers)}
    write_arff(results_to_dataset(results, dataset_name=name, specs=specs), stream)
