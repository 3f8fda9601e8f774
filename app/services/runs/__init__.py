"""Benchmark runs: planned (checked, stored ``queued``), executed (by the CLI at once, or by a
service worker later), resumed, cancelled; their leaderboards read from the store.

One module per reason to change:

- :mod:`.problem`: the engine's view of a run's data set, and its folds;
- :mod:`.memory`: the memory cap of a run's tasks;
- :mod:`.ranking`: the metric a run is ranked by;
- :mod:`.plan`: a request checked against its data set and stored (:func:`create_run`);
- :mod:`.execute`: a stored run carried out (:func:`execute_run`);
- :mod:`.stopping`: entries stopped early by a race, a budget or a stop;
- :mod:`.leaderboard`: a run's leaderboard from its stored results (:func:`run_leaderboard`),
  ranked once per version of a run's results for the web page (:func:`ranked_run`);
- :mod:`.independent`: each target of a multi-target data set benchmarked on its own.

The names below are the package's public face, what adapters and other services import.
"""

from touchbench.app.services.runs.execute import Callbacks, RunCancelled, execute_run
from touchbench.app.services.runs.independent import IndependentResult, independent_runs
from touchbench.app.services.runs.leaderboard import (
    NoResultsError,
    PerTargetSummary,
    RankedRun,
    RunLeaderboard,
    kept,
    per_target_summary,
    ranked_run,
    run_leaderboard,
)
from touchbench.app.services.runs.memory import task_memory
from touchbench.app.services.runs.plan import check_classifiers, create_run, default_classifiers
from touchbench.app.services.runs.problem import RunOptions, fold_plan, prepare_problem
from touchbench.app.services.runs.ranking import DEFAULT_METRIC, check_metric

__all__ = [
    "DEFAULT_METRIC",
    "Callbacks",
    "IndependentResult",
    "NoResultsError",
    "PerTargetSummary",
    "RankedRun",
    "RunCancelled",
    "RunLeaderboard",
    "RunOptions",
    "check_classifiers",
    "check_metric",
    "create_run",
    "default_classifiers",
    "execute_run",
    "fold_plan",
    "independent_runs",
    "kept",
    "per_target_summary",
    "prepare_problem",
    "ranked_run",
    "run_leaderboard",
    "task_memory",
]
