"""Runs and their leaderboards, as ``touchbench runs/bench/leaderboard --json`` print them
and the API answers them; and the request that starts a run (:class:`BenchRequest`)."""

from __future__ import annotations

from datetime import datetime
from typing import Any, Literal

from pydantic import Field, field_validator, model_validator

from touchbench.app.errors import FieldError
from touchbench.app.schemas.ablation import Grouping
from touchbench.app.schemas.base import Request, Schema
from touchbench.app.schemas.status import Status


class RunSchema(Schema):
    """A benchmark run: its data set, classifiers, protocol and progress."""

    id: int
    dataset: str = Field(description="Name of the data set.")
    dataset_id: int
    kind: str = Field(description="multiclass, multitarget or regression (numeric targets).")
    targets: list[str]
    classifiers: list[str]
    config: dict[str, Any] = Field(description="Folds, repeats, seed, timeout, ...")
    folds: str = Field(
        default="",
        description="How the folds were made, as the leaderboard's `folds` says it "
        "(`stratified 10-fold`, `leave-one-group-out, 7 groups`).",
    )
    status: Status
    created_at: datetime
    started_at: datetime | None = None
    finished_at: datetime | None = None
    tasks_done: int = Field(description="Tasks with a result (failed ones included).")
    tasks: int = Field(
        description="Tasks in all: (classifiers and the helpers of their ensembles) x folds "
        "x repeats."
    )
    tasks_failed: int = 0
    tasks_dropped: int = Field(
        default=0,
        description="Tasks that will not run: later folds of entries a race dropped or a "
        "total budget cut (tasks_done + tasks_dropped = tasks once such a run is done).",
    )
    error: str | None = Field(default=None, description="Why the run failed, if it did.")
    # Not the process executing it (host:pid, app/store/runs.py): the service's machine is
    # none of a client's business, with a write key or not (a cancel needs the run's id only;
    # a job's host is left out for the same reason, app/schemas/jobs.py).


class RunList(Schema):
    runs: list[RunSchema]


class RunCreated(Schema):
    """What ``POST /api/runs`` answers at once: the run waits for a worker."""

    id: int
    status: Status


class MetricValue(Schema):
    """Mean and sample standard deviation over the successful folds (``null``: none)."""

    mean: float | None
    std: float | None


PerTargetScores = dict[str, dict[str, MetricValue]]


class DropSchema(Schema):
    """Why a classifier stopped before its last fold."""

    reason: Literal["race", "budget", "not started"] = Field(
        description="race: significantly worse than the leader; budget: the run's total "
        "budget left no time for its next fold; not started: the run stopped (cancelled, "
        "interrupted) before any of its tasks began."
    )
    after_fold: int = Field(description="Folds it ran.")
    p_value: float | None = Field(description="The race's t-test against the leader.")
    leader: str | None = Field(description="The leader it was compared with.")
    mean: float | None = Field(description="Its mean of the ranking metric over its folds.")
    note: str = Field(description="`dropped after fold k (...)`, as every view says it.")


class OriginSchema(Schema):
    """How a run came by an entry's folds, when not by fitting an entry it asked for."""

    kind: Literal["from fold predictions", "helper"]
    entries: list[str] = Field(description="Its members, or the entries it serves.")
    note: str = Field(description="`from fold predictions of xgb, hgb`, as every view says it.")


class LeaderboardRowSchema(Schema):
    """One classifier's line; ``metrics.per_target`` holds a multi-target row's scores per
    target (target -> metric -> mean/std)."""

    rank: int
    classifier: str
    mark: Literal["v", "*", ""] = Field(description="v: better than the baseline; *: worse.")
    metrics: dict[str, MetricValue | PerTargetScores]
    n_ok: int
    n_failed: int
    errors: list[str]
    tested: bool = Field(
        default=False,
        description="Whether the t-test compared it with the baseline (false: the baseline, "
        "or a run beside whose folds do not pair with the baseline's: means only).",
    )
    run_id: int | None = Field(
        default=None, description="The run beside this one that the classifier comes from."
    )
    p_value: float | None = Field(
        default=None, description="The t-test's p-value against the baseline."
    )
    dropped: DropSchema | None = Field(
        default=None, description="Set when the classifier stopped before its last fold."
    )
    origin: OriginSchema | None = Field(
        default=None,
        description="Set when the run computed the entry from its members' fold predictions "
        "(`from fold predictions`) or fitted it only as a member of those (`helper`).",
    )


class RaceSchema(Schema):
    """How a raced run dropped classifiers."""

    alpha: float = Field(description="Level of the t-test against the leader.")
    test: str
    dropped: int = Field(description="Classifiers dropped.")
    note: str = Field(description="`raced at alpha 0.01 ...`, as every view says it.")


class BudgetSchema(Schema):
    """What a run's total budget cut."""

    minutes: float
    cut: list[str] = Field(description="Classifiers whose later folds were not started.")
    tasks_not_run: int = Field(description="Tasks of the run without a result.")
    minutes_spent: float = Field(
        default=0.0,
        description="Wall minutes the run's executions took (a resume gets what is left).",
    )
    note: str


class MarkSummary(Schema):
    better: int
    same: int
    worse: int


class FoldChoiceSchema(Schema):
    """What a tuned twin, a stack or an ensemble selection (its weights) chose on one outer
    training fold."""

    classifier: str
    repeat: int
    fold: int
    params: dict[str, Any]


class TunedComparisonSchema(Schema):
    """A tuned twin beside its default: means over the folds both completed, and the
    corrected resampled t-test of tuned against default."""

    tuned: str
    default: str
    metric: str
    tuned_mean: float | None
    default_mean: float | None
    n_folds: int
    t: float | None
    p: float | None
    mark: Literal["v", "*", ""] = Field(description="v: tuned significantly better; *: worse.")
    choices: list[FoldChoiceSchema]


#: How a run beside another is compared with it: ``paired`` (the same folds: the
#: corrected t-test is a paired test), ``by fold number`` (same data set, target, k and
#: repeats, but another fold assignment, e.g. WEKA's: the t-test pairs folds by number, an
#: approximation), ``means`` (folds that do not match: means only, no test).
BesideTest = Literal["paired", "by fold number", "means"]


class BesideSchema(Schema):
    """A run whose classifiers a leaderboard shows beside its own run's."""

    run_id: int
    name: str | None = Field(description="An imported run's name (the paper, the file).")
    origin: Literal["touchbench", "imported"]
    folds: str = Field(description="How that run's folds were made.")
    n_folds: int
    n_repeats: int
    test: BesideTest
    note: str = Field(description="Why the folds pair, or why they do not.")
    classifiers: dict[str, str] = Field(
        description="That run's classifier ids -> the names its rows have here (renamed "
        "when the leaderboard's run has the same id)."
    )


class LeaderboardSchema(Schema):
    """A run's ranked classifiers with WEKA's significance marks."""

    run_id: int
    dataset: str
    kind: str
    targets: list[str]
    status: Status
    folds: str = Field(
        default="",
        description="How the folds were made: `stratified 10-fold`, `10-fold` (shuffled), "
        "their group variants (recordings/sessions never straddle training and test), `x 3 "
        "repeats`, or `leave-one-group-out, 7 groups` (one fold per group).",
    )
    metric: str
    lower_is_better: bool = Field(
        default=False, description="Whether the ranking metric is better when smaller (mae)."
    )
    baseline: str | None = Field(description="The classifier the marks compare against.")
    summary: MarkSummary
    leaderboard: list[LeaderboardRowSchema]
    tuning: list[TunedComparisonSchema] = Field(
        default_factory=list, description="Tuned twins against their defaults (a run with `tune`)."
    )
    choices: list[FoldChoiceSchema] = Field(
        default_factory=list,
        description="What each tuned twin and stack chose per fold (`tune`, `stack`).",
    )
    beside: list[BesideSchema] = Field(
        default_factory=list,
        description="Runs whose classifiers are ranked beside this run's (`beside`), and "
        "how each is compared: t-test on paired folds, or means only.",
    )
    race: RaceSchema | None = Field(default=None, description="Set on a raced run.")
    budget: BudgetSchema | None = Field(
        default=None, description="Set on a run with a total budget."
    )
    aggregate: Aggregate = Field(
        default="window",
        description="What one prediction of the scores is: a window, or a recording's "
        "windows pooled (`recording`, see `notes`).",
    )
    notes: list[str] = Field(
        default_factory=list,
        description="What every view says under the table: how the scores were pooled, the "
        "race, the budget, classifiers that never started.",
    )


#: What a run scores as one prediction: each window, or each recording's windows pooled.
Aggregate = Literal["window", "recording"]

#: What a leaderboard says under its table of a run scored per recording.
PER_RECORDING_NOTE = (
    "scored per recording: each test recording's windows pooled into one prediction (the "
    "mean of their class probabilities; a majority vote for classifiers without "
    "probabilities; the mean prediction of numeric targets)"
)

#: The suites of classifiers a run may name instead of classifier ids.
Suite = Literal["fast", "default", "all"]

#: Largest memory cap of a task, in megabytes (1 TiB): finite, and a limit the OS can set.
MAX_MEMORY_MB = 2**20
#: Smallest memory cap of a task, in megabytes.
MIN_MEMORY_MB = 1
#: ``max_memory_mb`` that lifts the cap (``none`` on the command line, null in JSON).
NO_MEMORY_LIMIT = 0.0
#: Longest time limit of a task, in seconds (a week).
MAX_TIMEOUT = 7 * 24 * 3600.0
#: Time limit of a task unless the request gives one, in seconds: every use case that runs
#: tasks (a run, a learning curve) and every adapter's help reads it from here.
DEFAULT_TIMEOUT = 600.0

#: Folds a race runs before its first test (:data:`benchmark.run.racing.FIRST_ROUND`).
RACE_MIN_FOLDS = 3

#: Fields that a benchmark of each target on its own (``independent``) cannot honour.
_NOT_INDEPENDENT = {
    "target": "benchmarks every target",
    "weka": "runs the catalogue's multi-class classifiers on each target",
    "position": "classifies each target on its own, with no coordinates",
    "tune": "compares each target's plain classifiers",
    "budget": "compares each target's plain classifiers",
    "stack": "compares each target's plain classifiers",
    "ensemble": "compares each target's plain classifiers",
    "metric": "picks each target's best classifier by weighted F1",
    "baseline": "picks each target's best classifier by weighted F1",
    "race": "runs each target's classifiers to the end",
    "budget_total": "runs each target's classifiers to the end",
}


def id_as_text(value: Any) -> Any:
    """A data set's numeric id is one of its names (a request's ``dataset`` validator)."""
    if isinstance(value, int) and not isinstance(value, bool):
        return str(value)
    return value


#: ``folds`` of a leave-one-group-out run, and the other spelling it accepts.
LeaveOneGroupOut = Literal["logo"]
LOGO: LeaveOneGroupOut = "logo"
LOGO_ALIASES = frozenset({LOGO, "leave-one-group-out"})
#: Bounds of k in k-fold.
MIN_FOLDS, MAX_FOLDS = 2, 100


def folds_value(value: Any) -> Any:
    """A request's ``folds``: k (an int, or its digits as text), or leave-one-group-out
    under either of its names.

    Raises
    ------
    FieldError
        For ``folds``: neither a k between the bounds nor a name of leave-one-group-out.
    """
    if isinstance(value, str):
        text = value.strip().lower()
        if text in LOGO_ALIASES:
            return LOGO
        if not text.isdigit():
            raise FieldError(
                "folds", f"must be a number of folds or {LOGO} (leave-one-group-out), got '{value}'"
            )
        value = int(text)
    if isinstance(value, int) and not isinstance(value, bool):
        # pydantic's words for a bound, as every other field's refusal says it
        if value < MIN_FOLDS:
            bound = f"greater than or equal to {MIN_FOLDS}"
        elif value > MAX_FOLDS:
            bound = f"less than or equal to {MAX_FOLDS}"
        else:
            return value
        raise FieldError("folds", f"Input should be {bound} (or {LOGO}: leave-one-group-out)")
    raise FieldError("folds", f"must be a number of folds or {LOGO} (leave-one-group-out)")


def zero_is_no_limit(value: float | None) -> float | None:
    """A ``timeout`` of 0 means none (a request's ``timeout`` validator)."""
    return value or None


class BenchRequest(Request):
    """A benchmark run: what to cross-validate, how, and what to add to the classifiers.

    Every default, bound and rule across fields of a run is said here once; the rules
    that need the data set (a regression takes no `tune`, `stack` or `weka`, a stack
    needs one target, `independent` needs several nominal targets) are the service's
    (:func:`app.services.runs.create_run`) and name their field too.
    """

    dataset: str = Field(min_length=1, description="Data set name or id.")
    target: str | None = Field(
        default=None,
        min_length=1,
        description="Benchmark this one target (the multi-class catalogue; regressors if "
        "numeric); default: the data set's own targets.",
    )
    classifiers: list[str] | None = Field(
        default=None, min_length=1, max_length=500, description="Classifier ids to run."
    )
    suite: Suite | None = Field(
        default=None,
        description="A suite of classifiers instead of `classifiers`; `default` when neither "
        "is given (and no `weka`).",
    )
    weka: list[str] | None = Field(
        default=None,
        max_length=50,
        description='WEKA command lines to run as well, e.g. "weka.classifiers.trees.J48 -C '
        '0.1 -M 5" (J48, PART, NaiveBayes, IBk, ZeroR).',
    )
    position: list[str] | None = Field(
        default=None,
        min_length=2,
        max_length=3,
        description="2 or 3 numeric targets that are a position's coordinates: the run also "
        "scores the mean Euclidean error.",
    )
    folds: int | LeaveOneGroupOut = Field(
        default=10,
        description="k of k-fold cross-validation (2-100), or `logo` (alias "
        "`leave-one-group-out`): one fold per group of the data set (an import's group column, "
        "an extracted data set's recordings), that group on the test side; `repeats` must be 1.",
    )
    repeats: int = Field(default=1, ge=1, le=100, description="Repeats of the whole k-fold.")
    seed: int = Field(default=0, ge=0, le=2**31 - 1, description="Seed of folds and classifiers.")
    timeout: float | None = Field(
        default=DEFAULT_TIMEOUT,
        ge=0,
        le=MAX_TIMEOUT,
        description="Seconds one task may take before its worker is stopped; 0 or null: no limit.",
    )
    max_memory_mb: float | None = Field(
        default=None,
        ge=0,
        le=MAX_MEMORY_MB,
        description="Megabytes one task may allocate beyond its copy of the data before it "
        'fails (marked, the run goes on); 0, "none" or null: no limit; absent: the '
        "machine's available memory less a reserve, shared by the run's worker processes "
        "(derived when the run starts, stored as `task_memory_mb`).",
    )
    metric: str | None = Field(
        default=None,
        min_length=1,
        max_length=100,
        description="The metric the run's leaderboard ranks by; default: weighted F1, the "
        "Hamming score (several targets) or the mean absolute error (numeric targets).",
    )
    baseline: str | None = Field(
        default=None,
        min_length=1,
        max_length=200,
        description="The classifier the leaderboard's t-test compares against (one of the "
        "run's); default: the best.",
    )
    tune: bool = Field(
        default=False,
        description="Add a tuned twin (ID+tuned) of every classifier with a search space, "
        "searched inside each outer training fold (nested cross-validation).",
    )
    budget: float | None = Field(
        default=None,
        gt=0,
        le=1440,
        description="With `tune`: wall minutes each tuned twin's search may plan for in one "
        "outer fold; default: about 6 fits of the default setting.",
    )
    stack: int | None = Field(
        default=None,
        ge=1,
        le=20,
        description="Add stack-topN: in each outer training fold the run's N best "
        "classifiers by inner cross-validation, stacked by logistic regression (one target).",
    )
    ensemble: int | None = Field(
        default=None,
        ge=1,
        le=100,
        description="Add ensemble-N: in each outer training fold, N rounds of Caruana's "
        "greedy ensemble selection (with replacement) over the run's entries, chosen on "
        "their inner out-of-fold predictions of that training fold, computed from fold "
        "predictions (one nominal target).",
    )
    independent: bool = Field(
        default=False,
        description="Several targets: benchmark each target on its own with multi-class "
        "classifiers, one run per target, carried out at once rather than queued.",
    )
    race: bool = Field(
        default=False,
        description="Race the classifiers: every one on fold 1, then fold 2, ... (dear "
        "first); after each fold from the third, those significantly worse than the leader "
        "(corrected resampled t-test, its variances moderated across the fold's entries, at "
        "`race_alpha`) stop. The leader and the baseline never stop.",
    )
    race_alpha: float = Field(
        default=0.01,
        gt=0,
        lt=0.5,
        description="With `race`: the t-test's level for stopping a classifier.",
    )
    budget_total: float | None = Field(
        default=None,
        gt=0,
        le=MAX_TIMEOUT / 60,
        description="Wall minutes for the whole run: tasks run fold-major, cheap first, and "
        "a task whose predicted cost does not fit the time left is not started.",
    )
    aggregate: Aggregate = Field(
        default="window",
        description="What one prediction is: `window` (every window scored on its own) or "
        "`recording` (a recording's windows pooled: the mean of their class probabilities, "
        "a majority vote for classifiers without probabilities, the mean prediction of "
        "numeric targets). `recording` needs a data set extracted from recordings, one "
        "label per recording; its folds already keep each recording whole.",
    )

    _id_as_text = field_validator("dataset", mode="before")(id_as_text)
    _folds = field_validator("folds", mode="before")(folds_value)
    _zero_is_no_limit = field_validator("timeout", mode="after")(zero_is_no_limit)

    @model_validator(mode="before")
    @classmethod
    def _no_memory_limit(cls, data: Any) -> Any:
        """``max_memory_mb`` given as null or "none" is no limit (0); absent, the default
        cap (None), as a timeout of null is no limit and an absent one the default."""
        if isinstance(data, dict) and "max_memory_mb" in data:
            value = data["max_memory_mb"]
            if value is None or (isinstance(value, str) and value.strip().lower() == "none"):
                data = {**data, "max_memory_mb": NO_MEMORY_LIMIT}
        return data

    @field_validator("max_memory_mb", mode="after")
    @classmethod
    def _a_cap_or_none(cls, value: float | None) -> float | None:
        if value is not None and 0 < value < MIN_MEMORY_MB:
            raise FieldError(
                "max_memory_mb",
                f"Input should be greater than or equal to {MIN_MEMORY_MB}, or 0 or none "
                "for no limit",
            )
        return value

    @model_validator(mode="after")
    def _rules_across_fields(self) -> BenchRequest:
        if self.independent:
            for name, reason in _NOT_INDEPENDENT.items():
                if getattr(self, name) not in (None, False):
                    raise FieldError(name, f"is not used with `independent`, which {reason}")
        if self.classifiers and self.suite:
            raise FieldError("suite", "is not used with `classifiers`: give one or the other")
        if self.budget is not None and not self.tune:
            raise FieldError("budget", "is only meaningful with `tune`")
        if self.folds == LOGO and self.repeats != 1:
            raise FieldError(
                "repeats",
                f"must be 1 with `folds` {LOGO} (leave-one-group-out makes one partition, "
                f"the same every time), got {self.repeats}",
            )
        if self.race and isinstance(self.folds, int) and self.folds * self.repeats < RACE_MIN_FOLDS:
            raise FieldError(
                "race",
                f"needs at least {RACE_MIN_FOLDS} folds in all (it first tests after the "
                f"third); `folds` {self.folds} x {self.repeats} repeat(s) is too few",
            )
        if self.independent and self.aggregate == "recording":
            raise FieldError(
                "aggregate", "is not used with `independent`, which scores every window"
            )
        if "race_alpha" in self.model_fields_set and not self.race:
            raise FieldError("race_alpha", "is only meaningful with `race`")
        return self


class BenchHereRequest(Request):
    """A run carried out at once by the process that asks (``touchbench bench``): a new one
    (``bench``) or a stored one to finish (``resume``), then, if asked, its ablation as a
    job the store keeps (``ablate_groups``)."""

    bench: BenchRequest | None = Field(default=None, description="A new run.")
    resume: int | None = Field(
        default=None, ge=1, description="A stored run whose tasks without a result to carry out."
    )
    ablate_groups: Grouping | None = Field(
        default=None,
        description="Then rerun the run's classifiers on its folds without each group of "
        "features (an ablation's `grouping`).",
    )

    @model_validator(mode="after")
    def _one_run(self) -> BenchHereRequest:
        if (self.bench is None) == (self.resume is None):
            raise FieldError("resume", "give a new run or a run to resume, one of the two")
        if self.ablate_groups is not None and self.bench is not None and self.bench.independent:
            raise FieldError("ablate_groups", "is not used with `independent`")
        return self
