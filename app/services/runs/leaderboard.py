"""A run's leaderboard from its stored results: ranked, marked against a baseline, with runs
beside it, per-target scores and what the race, the budget or a stop left out.
"""

from __future__ import annotations

# Imports inside functions: start-up time: the statistics (scipy) load when a leaderboard
# is first built, not when the API's routes or the listing commands import this module.
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from touchbench.app.schemas.runs import (
    PER_RECORDING_NOTE,
    BudgetSchema,
    FoldChoiceSchema,
    LeaderboardRowSchema,
    LeaderboardSchema,
    MarkSummary,
    RaceSchema,
    TunedComparisonSchema,
)
from touchbench.app.schemas.status import UNFINISHED, Status
from touchbench.app.services.beside import Beside, besides, merged_results, row_runs
from touchbench.app.services.runs.ranking import check_metric, run_metric
from touchbench.app.services.runs.stopping import RACE_TEST, never_started
from touchbench.app.store.database import Store
from touchbench.app.store.drops import load_drops
from touchbench.app.store.runs import RunInfo, get_run, load_results
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.results import Drop, Origin, TaskResult

if TYPE_CHECKING:  # scipy.stats (significance) loads when a leaderboard is first built
    from touchbench.benchmark.evaluation.leaderboard import Leaderboard


#: Why a run has no results yet, when it is under way (:data:`app.schemas.status.UNFINISHED`).
_UNDER_WAY = {
    Status.QUEUED: "it waits for a worker",
    Status.RUNNING: "it is still running",
    Status.CANCELLING: "it is being cancelled",
}


class NoResultsError(ConfigurationError):
    """A run without a stored result has no leaderboard yet.

    Attributes
    ----------
    under_way : bool
        The run is queued, running or being cancelled (resuming it would not help).
    """

    def __init__(self, run: RunInfo) -> None:
        hint = _UNDER_WAY.get(run.status, f"it is {run.status}; resuming it carries it out")
        super().__init__(f"run {run.id} has no results yet ({hint})")
        self.run = run
        self.under_way = run.status in UNFINISHED


@dataclass(frozen=True)
class RunLeaderboard:
    """A run, its stored results and their leaderboard.

    Attributes
    ----------
    run : RunInfo
    board : Leaderboard
        The run's classifiers ranked, with WEKA's marks against a baseline.
    results : list of TaskResult
        Every stored fold result of the run, read once.
    besides : tuple of Beside
        Runs ranked beside this one (an imported paper's results), with how each is
        compared; their results are in ``board`` but not in ``results``.
    drops : dict of str to Drop
        The classifiers that stopped before their last fold (raced or budgeted runs).
    """

    run: RunInfo
    board: Leaderboard
    results: list[TaskResult]
    besides: tuple[Beside, ...]
    drops: dict[str, Drop]

    @property
    def per_recording(self) -> bool:
        """Whether the run scored each recording's windows as one prediction."""
        return self.run.config.by_recording

    def notes(self) -> list[str]:
        """What the leaderboard of a run scored per recording, raced, budgeted or stopped
        says under its table."""
        notes = [PER_RECORDING_NOTE] if self.per_recording else []
        helpers = self.run.config.helpers
        if helpers:
            spent = sum(
                r.metrics.get("fit_time", 0.0) + r.metrics.get("predict_time", 0.0)
                for r in self.results
                if r.ok and r.key.classifier in helpers
            )
            notes.append(
                f"fitted only as members of ensembles: {', '.join(helpers)} "
                f"({spent:.1f} s of fitting and predicting in all)"
            )
        notes += [part.note for part in (self.race(), self.budget()) if part is not None]
        unstarted = [c for c, d in self.drops.items() if d.reason == "not started"]
        if unstarted:
            more = f" and {len(unstarted) - 10} more" if len(unstarted) > 10 else ""
            notes.append(
                f"{len(unstarted)} classifier(s) never started (the run is {self.run.status}): "
                f"{', '.join(unstarted[:10])}{more}"
            )
        return notes

    def race(self) -> RaceSchema | None:
        """How the run raced; ``None`` for a run that did not."""
        race = self.run.config.race
        if race is None:
            return None
        alpha = race.alpha
        dropped = sum(1 for d in self.drops.values() if d.reason == "race")
        return RaceSchema(
            alpha=alpha,
            test=RACE_TEST,
            dropped=dropped,
            note=f"raced at alpha {alpha:g} ({RACE_TEST}); {dropped} dropped",
        )

    def budget(self) -> BudgetSchema | None:
        """What the run's total budget cut; ``None`` for a run without one."""
        minutes = self.run.config.budget_total
        if minutes is None:
            return None
        cut = [c for c, d in self.drops.items() if d.reason == "budget"]
        raced_out = sum(
            self.run.config.tasks_per_entry(len(self.run.classifiers)) - d.after_fold
            for d in self.drops.values()
            if d.reason == "race"
        )
        missing = max(self.run.n_tasks - len(self.results) - raced_out, 0)
        cut_text = f"; cut: {', '.join(cut)}" if cut else ""
        return BudgetSchema(
            minutes=minutes,
            cut=cut,
            tasks_not_run=missing,
            minutes_spent=self.run.seconds_spent / 60.0,
            note=f"total budget {minutes:g} min: {missing} task(s) not run{cut_text}",
        )

    def report(self) -> LeaderboardSchema:
        """What ``leaderboard --json`` prints and the API serves: rows with their per-target
        scores, tuned twins against their defaults, the choices per fold."""
        from touchbench.benchmark.evaluation.tuned import compare_tuned, fold_choices

        run, board, results = self.run, self.board, self.results
        per_target = per_target_summary(results)
        data = board.to_json()
        origins = row_runs(self.besides)
        for row in data["leaderboard"]:
            row["run_id"] = origins.get(row["classifier"])
            targets = per_target.get(row["classifier"])
            if targets:
                row["metrics"]["per_target"] = {
                    target: {
                        name: {"mean": mean, "std": std} for name, (mean, std) in scores.items()
                    }
                    for target, scores in targets.items()
                }
        return LeaderboardSchema(
            run_id=run.id,
            dataset=run.dataset_name,
            kind=run.kind,
            targets=run.targets,
            status=run.status,
            folds=run.folds_text,
            metric=data["metric"],
            lower_is_better=data["lower_is_better"],
            baseline=data["baseline"],
            summary=MarkSummary(**data["summary"]),
            leaderboard=[LeaderboardRowSchema(**row) for row in data["leaderboard"]],
            tuning=[
                TunedComparisonSchema(**c.to_json())
                for c in compare_tuned(results, metric=board.metric, alpha=board.alpha)
            ],
            choices=[FoldChoiceSchema(**c.to_json()) for c in fold_choices(results)],
            beside=[b.schema() for b in self.besides],
            race=self.race(),
            budget=self.budget(),
            aggregate="recording" if self.per_recording else "window",
            notes=self.notes(),
        )


def run_leaderboard(
    store: Store,
    run_id: int | str,
    *,
    metric: str | None = None,
    baseline: str | None = None,
    beside: Sequence[int | str] = (),
) -> RunLeaderboard:
    """A run's leaderboard from its stored results.

    Parameters
    ----------
    metric, baseline : str, optional
        Rank by this metric, mark against this classifier; default: what the run was
        asked to rank by, else its kind's metric and its best classifier.
    beside : sequence of run ids
        Runs of the same data set and target whose classifiers are ranked too (an
        imported paper's results): t-tested where their folds pair with the run's, by
        their means otherwise (:mod:`app.services.beside`).

    Raises
    ------
    NoResultsError
        The run has no result yet.
    ConfigurationError
        A metric of the other kind of problem; an unknown metric or baseline.
    """
    from touchbench.benchmark.evaluation.leaderboard import build_leaderboard

    run = get_run(store, run_id)
    results = load_results(store, run.id)
    if not results:
        raise NoResultsError(run)
    if metric is not None:
        check_metric(run.kind, metric, position=bool(run.config.position), run_id=run.id)
    metric = metric or run_metric(run)
    others = besides(run, [get_run(store, ref) for ref in dict.fromkeys(beside)])
    ranked, groups = merged_results(results, [(b, load_results(store, b.run.id)) for b in others])
    drops = {**never_started(run, results), **load_drops(store, run.id)}
    board = build_leaderboard(
        ranked,
        metric=metric,
        baseline=baseline or run.config.baseline,
        groups=groups if others else None,
        drops=drops,
        origins=run_origins(run),
    )
    return RunLeaderboard(run, board, results, tuple(others), drops)


def run_origins(run: RunInfo) -> dict[str, Origin]:
    """How the run came by the folds of its computed entries and helpers, as planned."""
    return {
        entry: Origin(origin.kind, tuple(origin.entries))
        for entry, origin in run.config.origins.items()
    }


PerTargetSummary = dict[str, dict[str, dict[str, tuple[float, float]]]]


def per_target_summary(results: Sequence[TaskResult]) -> PerTargetSummary:
    """Mean and standard deviation over folds of each target's scores, per classifier.

    Returns
    -------
    dict
        classifier -> target -> metric (accuracy, f1_weighted, ...) -> (mean, std).
    """
    collected: dict[str, dict[str, dict[str, list[float]]]] = {}
    for result in results:
        if result.status != "ok" or not result.per_target:
            continue
        by_target = collected.setdefault(result.key.classifier, {})
        for target, scores in result.per_target.items():
            for name, value in scores.items():
                by_target.setdefault(target, {}).setdefault(name, []).append(value)
    return {
        classifier: {
            target: {
                name: (
                    float(np.mean(values)),
                    float(np.std(values, ddof=1)) if len(values) > 1 else float("nan"),
                )
                for name, values in scores.items()
            }
            for target, scores in targets.items()
        }
        for classifier, targets in collected.items()
    }
