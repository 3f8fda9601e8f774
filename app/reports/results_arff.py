"""A run's per-fold results as WEKA Experimenter's InstanceResultListener ARFF."""

from __future__ import annotations

from typing import TextIO

from touchbench.app.reports.leaderboard import row_note
from touchbench.app.services.runs import RunLeaderboard
from touchbench.app.services.tuning import run_specs
from touchbench.benchmark.catalogue import CATALOGUE
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.evaluation.results_arff import results_to_dataset
from touchbench.benchmark.io.arff import write_arff


def write_results_arff(ranked: RunLeaderboard, stream: TextIO) -> None:
    """Write every successful fold of a multi-class run, one row per (run, fold, scheme).

    A raced or budgeted run's file opens with ``%`` comments (which WEKA skips) saying how
    it raced and which classifiers stopped early, after which fold and why.
    """
    run = ranked.run
    if run.kind != "multiclass":
        what = "a regression" if run.kind == "regression" else "multi-target"
        raise ConfigurationError(
            f"run {run.id} is {what}; WEKA's results format holds multi-class runs "
            "(the csv and json formats hold every kind)"
        )
    name = f"{run.dataset_name}: {', '.join(run.targets)}"
    specs = {**CATALOGUE, **run_specs(run.config, run.classifiers)}
    notes = ranked.notes() + [
        f"{row.classifier}: {row_note(row)}" for row in ranked.board.rows if row.dropped
    ]
    for note in notes:
        stream.write(f"% {note}\n")
    write_arff(results_to_dataset(ranked.results, dataset_name=name, specs=specs), stream)
