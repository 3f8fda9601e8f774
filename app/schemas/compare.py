"""The JSON of a comparison across runs (``touchbench compare --json``, and the API)."""

from __future__ import annotations

import math
from typing import Literal

from app.schemas.base import Schema
from app.services.compare import Comparison, PairComparison
from benchmark.evaluation.bayesian import BayesianComparison


class ClassifierRank(Schema):
    """One classifier's place: average rank and its score on every block."""

    classifier: str
    average_rank: float
    mean_score: float | None
    scores: dict[str, float | None]


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

    @classmethod
    def of(cls, pair: PairComparison) -> PairOut:
        return cls(
            first=pair.a,
            second=pair.b,
            per_run=[
                BayesianOut.of(result, block=scores.label, run_id=scores.run.id)
                for scores, result in pair.per_run
            ],
            across_runs=BayesianOut.of(pair.across) if pair.across else None,
        )


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

    @classmethod
    def of(cls, comparison: Comparison) -> ComparisonOut:
        ranks = comparison.ranks
        table = comparison.table
        names = list(ranks.classifiers)
        completed = comparison.completed
        return cls(
            runs=[scores.run.id for scores in comparison.runs],
            metric=comparison.metric,
            lower_is_better=comparison.lower_is_better,
            alpha=ranks.alpha,
            blocks_are=comparison.blocks_are,
            blocks=list(ranks.blocks),
            classifiers=[
                ClassifierRank(
                    classifier=name,
                    average_rank=float(rank),
                    mean_score=_finite(float(mean)),
                    scores={
                        block: _finite(float(value))
                        for block, value in zip(table.blocks, table.column(name), strict=True)
                    },
                )
                for name, rank, mean in zip(
                    names, ranks.average_ranks, ranks.mean_scores, strict=True
                )
            ],
            friedman=FriedmanOut(
                chi_square=ranks.friedman.statistic,
                p_value=ranks.friedman.p_value,
                iman_davenport_f=_finite(ranks.friedman.iman_davenport),
                iman_davenport_p_value=ranks.friedman.iman_davenport_p_value,
                df=ranks.friedman.df,
                df_denominator=ranks.friedman.df_denominator,
                tie_corrected=ranks.friedman.tie_corrected,
            ),
            nemenyi=NemenyiOut(
                q_alpha=ranks.q_alpha,
                critical_difference=ranks.critical_difference,
                groups=[list(group) for group in ranks.groups],
                p_values={
                    a: {b: float(ranks.nemenyi_p_values[i, j]) for j, b in enumerate(names)}
                    for i, a in enumerate(names)
                },
            ),
            holm=HolmOut(
                control=ranks.control,
                comparisons=[
                    HolmRow(
                        classifier=h.classifier,
                        z=h.z,
                        p_value=h.p_value,
                        adjusted_p_value=h.adjusted_p_value,
                        significant=h.significant,
                    )
                    for h in ranks.holm
                ],
            ),
            missing=MissingOut(
                policy=completed.policy,
                cells=[
                    MissingCellOut(block=m.block, classifier=m.classifier)
                    for m in completed.missing
                ],
                dropped_classifiers=completed.dropped_classifiers,
                dropped_blocks=completed.dropped_blocks,
            ),
            not_shared=comparison.not_shared,
            bayesian=PairOut.of(comparison.pair) if comparison.pair else None,
            notes=comparison.notes,
        )


def _finite(value: float) -> float | None:
    return value if math.isfinite(value) else None
