"""What the engine computes on: a run's problem (numeric features, target codes) and its folds,
from a data set and the run's options; the same for a resumed run and for the answers
after a run (ablation, importance, learning curves).
"""

from __future__ import annotations

# Imports inside functions: start-up time: the fold plans load scikit-learn's splitters
# when a run first makes its folds.
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from touchbench.app.errors import FieldError
from touchbench.app.schemas.run_config import LEAVE_ONE_GROUP_OUT, RunConfig, Split
from touchbench.app.schemas.runs import LOGO, BenchRequest
from touchbench.benchmark.dataset import Dataset
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.problem import Problem, problem_from_dataset, restrict_targets

if TYPE_CHECKING:
    from touchbench.benchmark.run.folds import FoldPlan


@dataclass(frozen=True)
class RunOptions:
    """How a run cross-validates, as its stored config says: what a resumed run gets back.

    The defaults and bounds are the request's (:class:`app.schemas.runs.BenchRequest`); a
    run's stored configuration (:class:`app.schemas.run_config.RunConfig`) keeps them.

    Attributes
    ----------
    folds, repeats, seed : int
        k of k-fold (unused by leave-one-group-out), repetitions of the whole partition,
        seed of folds and classifiers.
    timeout : float or None
        Seconds one task may take before its worker process is killed; ``None``: no limit.
    max_memory_mb : float or None
        Megabytes one task may allocate beyond its worker's copy of the data; 0: no limit;
        None: derived from the machine when the run starts
        (:func:`app.services.runs.memory.task_memory`).
    split : {"k-fold", "leave-one-group-out"}
        How the instances are split: k folds, or one fold per group.
    """

    folds: int
    repeats: int
    seed: int
    timeout: float | None
    max_memory_mb: float | None
    split: Split = "k-fold"

    @classmethod
    def from_request(cls, request: BenchRequest) -> RunOptions:
        logo = request.folds == LOGO
        return cls(
            # leave-one-group-out makes as many folds as groups, whatever k says
            folds=0 if logo else int(request.folds),
            split=LEAVE_ONE_GROUP_OUT if logo else "k-fold",
            repeats=request.repeats,
            seed=request.seed,
            timeout=request.timeout,
            max_memory_mb=request.max_memory_mb,
        )

    @classmethod
    def from_config(cls, config: RunConfig) -> RunOptions:
        """The options a run was planned with.

        Raises
        ------
        ConfigurationError
            The configuration has no folds or repeats (an imported run's may lack them).
        """
        if config.asked_folds is None or config.repeats is None:
            raise ConfigurationError("the run's configuration does not say its folds")
        return cls(
            folds=config.asked_folds,
            repeats=config.repeats,
            seed=config.seed,
            timeout=config.timeout,
            max_memory_mb=config.max_memory_mb,
            split=config.split,
        )


@dataclass
class PreparedProblem:
    problem: Problem
    target_names: list[str]
    warnings: list[str] = field(default_factory=list)


class OneValueError(ConfigurationError):
    """A numeric target with a single value: a regression has nothing to predict."""

    def __init__(self, target: str, value: float) -> None:
        super().__init__(
            f"numeric target '{target}' has a single value ({value:g}): nothing to predict"
        )
        self.target = target
        self.value = value


def prepare_problem(
    dataset: Dataset, targets: Sequence[str] | None = None, position: Sequence[str] = ()
) -> PreparedProblem:
    """The engine's view of a data set: numeric X, integer target codes (or target values
    of a regression), nominal columns.

    Parameters
    ----------
    dataset : Dataset
    targets : sequence of str, optional
        Target attributes to predict; the data set's own targets by default (the others
        are left out, never used as features).
    position : sequence of str
        2 or 3 numeric targets that are a position's coordinates.
    """
    if dataset.n_instances == 0:
        raise ConfigurationError(f"dataset '{dataset.name}' has no instances")
    restricted = restrict_targets(dataset, targets)
    problem, warnings = problem_from_dataset(restricted, position=position)
    if problem.kind == "regression":
        for column, name in zip(problem.Y.T, problem.target_names, strict=True):
            if problem.n_instances and np.ptp(column) == 0:
                raise OneValueError(name, float(column[0]))
        return PreparedProblem(problem, list(problem.target_names), warnings)
    for column, target in zip(problem.Y.T, restricted.schema.targets, strict=True):
        present = np.unique(column)
        if present.size < 2:
            only = target.values[int(present[0])] if present.size else "none"
            raise ConfigurationError(
                f"target '{target.name}' has a single class ('{only}'): nothing to classify"
            )
    return PreparedProblem(problem, list(problem.target_names), warnings)


def fold_plan(prepared: PreparedProblem, options: RunOptions) -> FoldPlan:
    """The folds a run with these options makes on this problem (the same on resume).

    Raises
    ------
    FieldError
        For ``folds``: leave-one-group-out on data without groups (or with one group), or
        folds the data cannot be split into.
    ConfigurationError
        The problem itself cannot be cross-validated (a target with one class).
    """
    from touchbench.benchmark.run.folds import make_fold_plan

    logo = options.split == LEAVE_ONE_GROUP_OUT
    if logo and prepared.problem.groups is None:
        raise FieldError(
            "folds",
            f"{LOGO} (leave-one-group-out) needs groups, and the data set has none: name a "
            "group column on import, or extract the data set from recordings (each "
            "recording is a group)",
        )
    try:
        return make_fold_plan(
            prepared.problem.Y,
            n_folds=options.folds,
            n_repeats=options.repeats,
            seed=options.seed,
            groups=prepared.problem.groups,
            target_names=prepared.target_names,
            regression=prepared.problem.kind == "regression",
            split=options.split,
        )
    except ConfigurationError as error:
        if logo and "group" in str(error):
            raise FieldError("folds", str(error)) from None
        raise
    except ValueError as error:  # scikit-learn's splitters on data too small to split
        raise FieldError("folds", f"cannot make {options.folds} folds: {error}") from None
