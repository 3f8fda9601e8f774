"""A run's stored configuration: what it was asked and what its planning decided, read back
by its execution, a resume, its leaderboard and the answers after it.

:class:`RunConfig` is the one reader and writer of the ``config`` column of the runs table.
Its fields are the JSON keys every version of touchbench wrote; a store written by older
code holds fewer of them, and each key it lacks takes the default that code meant (an old
run has no ``aggregate``: it scored windows).  :meth:`RunConfig.to_json` writes back exactly
the keys a configuration was given, so that a run reads as it was stored, and keys this
version does not know are kept as they are.
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field

from touchbench.app.schemas.runs import Aggregate

#: How a run's instances are split into folds: k folds (stratified and group-aware where
#: they can be), or one fold per group (:data:`benchmark.run.folds.Split`, said again here
#: because the schemas stand below the engine and load nothing of it).
Split = Literal["k-fold", "leave-one-group-out"]
LEAVE_ONE_GROUP_OUT: Split = "leave-one-group-out"

#: ``origin`` of an imported run (runs touchbench carried out have none).
IMPORTED = "imported"


def entry_tasks(n_tasks: int, n_entries: int) -> int:
    """Tasks of each of a run's ``n_entries`` entries (its classifiers and helpers) when it
    has ``n_tasks`` in all."""
    return n_tasks // max(n_entries, 1)


class _Stored(BaseModel):
    """A part of a stored configuration: immutable, and lenient towards keys it does not
    know (written by another version), which it keeps."""

    model_config = ConfigDict(frozen=True, extra="allow")


class RaceConfig(_Stored):
    """How a raced run drops classifiers."""

    alpha: float = Field(description="Level of the t-test against the leader.")


class TuneConfig(_Stored):
    """How a run's tuned twins search."""

    budget_minutes: float | None = Field(
        default=None, description="Wall minutes a twin's search may plan for per outer fold."
    )


class ImportedScheme(_Stored):
    """One WEKA scheme of an imported results file."""

    classifier: str
    scheme: str = ""
    options: str = ""
    version: str = ""


class OriginConfig(_Stored):
    """How a run comes by an entry's folds when not by fitting an entry it asked for
    (:class:`benchmark.results.Origin`)."""

    kind: Literal["from fold predictions", "helper"] = Field(
        description="`from fold predictions`: computed from its members' fold predictions; "
        "`helper`: a member the run did not ask for, fitted once per fold for its ensembles."
    )
    entries: list[str] = Field(description="Its members, or the entries it serves.")


class ExtraSpecsConfig(_Stored):
    """What a run adds to the catalogue: enough to build its extra classifier specs again
    (:func:`app.services.tuning.run_specs`)."""

    weka: dict[str, str | None] = Field(
        default_factory=dict, description="Id of each WEKA command line's entry -> the line."
    )
    tune: TuneConfig | None = Field(default=None, description="Set when tuned twins were added.")
    stack: int | None = Field(default=None, description="TOP_N of the stack added, if any.")
    ensemble: int | None = Field(
        default=None, description="Rounds of the ensemble selection added (ensemble-N), if any."
    )


class RunConfig(ExtraSpecsConfig):
    """A run's stored configuration (see the module's notes on older stores).

    The fields of a run touchbench carried out come from its request
    (:class:`app.schemas.runs.BenchRequest`) and its planning
    (:mod:`app.services.runs.plan`); an imported run has ``origin`` ``imported`` and its
    own few (:mod:`app.services.imported`).
    """

    # How it cross-validates (what a resume gets back).
    folds: int | None = Field(
        default=None,
        description="Folds per repeat the data allowed (leave-one-group-out: its groups).",
    )
    split: Split = Field(
        default="k-fold",
        description="How the folds were made: k-fold, or one fold per group "
        "(leave-one-group-out); an old store's runs are k-fold.",
    )
    folds_requested: int | None = Field(
        default=None, description="Folds per repeat asked (absent: as many as `folds`)."
    )
    repeats: int | None = None
    seed: int = 0
    timeout: float | None = Field(default=None, description="Seconds per task; null: no limit.")
    max_memory_mb: float | None = Field(
        default=None, description="The cap asked; 0: no limit; null: derived at the start."
    )

    # What it predicts from what.
    targets_given: list[str] | None = Field(
        default=None, description="The one target asked (`target`); null: the data set's own."
    )
    position: list[str] | None = None
    n_instances: int | None = None
    grouped: bool = False
    fold_scheme: str | None = None
    n_tasks: int = 0

    # Its classifiers (with ``weka``, ``tune``, ``stack`` and ``ensemble``).
    suite: str | None = None
    helpers: list[str] = Field(
        default_factory=list,
        description="Members of its ensembles that it did not ask for, fitted for them "
        "(their tasks count in `n_tasks`).",
    )
    origins: dict[str, OriginConfig] = Field(
        default_factory=dict,
        description="Its entries computed from fold predictions and its helpers, as planned "
        "(absent in runs of older versions, whose ensembles were fitted).",
    )

    # How its leaderboard ranks, and what stops its entries early.
    metric: str | None = None
    baseline: str | None = None
    race: RaceConfig | None = None
    budget_total: float | None = None
    aggregate: Aggregate = "window"

    # Decided by the process executing it, when it starts.
    task_memory_mb: int | None = None
    task_memory_from: str | None = None

    # An imported run.
    origin: str | None = None
    name: str | None = None
    source: str | None = None
    key_dataset: str | None = None
    schemes: list[ImportedScheme] = Field(default_factory=list)

    @classmethod
    def load(cls, stored: dict[str, Any]) -> RunConfig:
        """The configuration a store holds (written by this version or an older one)."""
        return cls.model_validate(stored)

    def to_json(self) -> dict[str, Any]:
        """What the store keeps and a run's JSON shows: the keys given, and no others."""
        return self.model_dump(mode="json", exclude_unset=True)

    def updated(self, **values: Any) -> RunConfig:
        """This configuration with ``values`` set (validated)."""
        return RunConfig.load({**self.to_json(), **values})

    @property
    def imported(self) -> bool:
        """Whether the run's results were imported rather than computed here."""
        return self.origin == IMPORTED

    @property
    def by_recording(self) -> bool:
        """Whether the run scores each recording's windows as one prediction."""
        return self.aggregate == "recording"

    def tasks_per_entry(self, n_classifiers: int) -> int:
        """Tasks of each entry of a run with ``n_classifiers`` classifiers (its helpers
        have as many)."""
        return entry_tasks(self.n_tasks, n_classifiers + len(self.helpers))

    @property
    def asked_folds(self) -> int | None:
        """The folds per repeat asked: what a resume makes its fold plan with."""
        return self.folds_requested if self.folds_requested is not None else self.folds
