"""The JSON of a comparison across runs (``touchbench compare --json``, and the API)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Literal

from pydantic import Field

from touchbench.app.schemas.base import Schema

if TYPE_CHECKING:  # the test's module loads SciPy's distributions: not for a schema
    from touchbench.benchmark.evaluation.bayesian import BayesianComparison


class ClassifierRank(Schema):
    """One classifier's place: average rank and its score on every block."""

    classifier: str
    average_rank: float
    mean_score: float | None
    scores: dict[str, float | None]
    origin: str | None = Field(
        default=None,
        description="Set when a run computed it from fold predictions (or fitted it as a "
        "helper): `from fold predictions of xgb, hgb (run 3)`.",
    )


class FriedmanOut(Schema):
    chi_square: float
    p_value: float
    iman_davenport_f: float | None
    iman_davenport_p_value: float
    df: int
    df_denominator: int
    tie_corrected: bool


class NemenyiOut(Schema):
    q_alpha: float
    critical_difference: float
    groups: list[list[str]]
    p_values: dict[str, dict[str, float]]


class HolmRow(Schema):
    classifier: str
    z: float
    p_value: float
    adjusted_p_value: float
    significant: bool


class HolmOut(Schema):
    control: str
    comparisons: list[HolmRow]


class MissingCellOut(Schema):
    block: str
    classifier: str


class MissingOut(Schema):
    policy: str
    cells: list[MissingCellOut]
    dropped_classifiers: list[str]
    dropped_blocks: list[str]


class BayesianOut(Schema):
    """``p_left``: the first classifier better by more than ``rope``; ``p_right``: the
    second."""

    test: str
    block: str | None
    run_id: int | None
    p_left: float
    p_rope: float
    p_right: float
    rope: float
    mean_difference: float
    n: int
    decision: str

    @classmethod
    def of(
        cls, result: BayesianComparison, *, block: str | None = None, run_id: int | None = None
    ) -> BayesianOut:
        return cls(
            test=result.test,
            block=block,
            run_id=run_id,
            p_left=result.p_left,
            p_rope=result.p_rope,
            p_right=result.p_right,
            rope=result.rope,
            mean_difference=result.mean_difference,
            n=result.n,
            decision=result.decision(),
        )


class PairOut(Schema):
    first: str
    second: str
    per_run: list[BayesianOut]
    across_runs: BayesianOut | None


class ComparisonOut(Schema):
    """Classifiers ranked over the blocks of some runs (Demšar 2006)."""

    runs: list[int]
    metric: str
    lower_is_better: bool
    alpha: float
    blocks_are: Literal["datasets", "folds"]
    blocks: list[str]
    classifiers: list[ClassifierRank]
    friedman: FriedmanOut
    nemenyi: NemenyiOut
    holm: HolmOut
    missing: MissingOut
    not_shared: list[str]
    bayesian: PairOut | None
    notes: list[str]
