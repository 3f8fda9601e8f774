"""Entries that stop before their last fold: a race drops those significantly worse than the
leader, a total budget cuts what no longer fits, and a run stopped early (cancelled,
interrupted) leaves the rest never started.
"""

from __future__ import annotations

# Imports inside functions: start-up time: the race's rule loads the engine's racing
# (scipy) when a raced run starts.
from collections.abc import Sequence
from typing import TYPE_CHECKING

from touchbench.app.schemas.status import STOPPED_EARLY
from touchbench.app.services.runs.ranking import run_metric
from touchbench.app.store.runs import RunInfo
from touchbench.benchmark.results import Drop, TaskResult

if TYPE_CHECKING:
    from touchbench.benchmark.run.racing import RaceRule


#: The race's test, as the leaderboards name it.
RACE_TEST = "corrected resampled t-test against the leader, variances moderated"


#: Seconds a resumed run whose total budget is spent gets: positive for the engine, too
#: short for any task to fit, so that every entry left is cut and the leaderboard says so.
NO_BUDGET_LEFT = 1e-6


def budget_left(run: RunInfo) -> float | None:
    """Seconds of the run's total budget its earlier executions left; ``None`` without one."""
    minutes = run.config.budget_total
    if minutes is None:
        return None
    return max(minutes * 60.0 - run.seconds_spent, NO_BUDGET_LEFT)


def race_rule(run: RunInfo) -> RaceRule | None:
    """How a run races, from its config: its ranking metric, level and baseline; ``None``
    for a run that is not raced."""
    race = run.config.race
    if race is None:
        return None
    from touchbench.benchmark.run.racing import RaceRule

    baseline = run.config.baseline
    return RaceRule(
        metric=run_metric(run),
        alpha=race.alpha,
        protected=frozenset({baseline} if baseline else ()),
    )


def never_started(run: RunInfo, results: Sequence[TaskResult]) -> dict[str, Drop]:
    """The entries of a run stopped early (cancelled, interrupted) that have no result, by
    id: a leaderboard lists them (marked ``never started``) rather than leave them out."""
    if run.status not in STOPPED_EARLY:
        return {}
    started = {result.key.classifier for result in results}
    return {c: Drop(c, "not started", 0) for c in run.classifiers if c not in started}
