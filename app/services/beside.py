"""Other runs' classifiers ranked beside a run's: the paper's WEKA results beside ours.

Whether a t-test may compare two runs' classifiers depends on their folds:

- ``paired``: both runs were carried out here on the same data set and target with the
  same fold scheme, k, repeats, seed and instances, so fold *i* of one is fold *i* of the
  other (the same test instances): the corrected resampled t-test is a paired test.
- ``by fold number``: same data set, target, k and repeats, but the fold assignments differ
  (an imported run: WEKA's Experimenter shuffles with its own generator, never ours).  The
  corrected t-test pairs fold *i* with fold *i*; both folds are test sets of the same size
  from the same data, so it is an approximation of the paired test, said as such.
- ``means``: anything else (another k, another number of repeats): only the means compare,
  no test, no mark.

Runs on another data set or target are refused: their scores do not compare at all
(``compare`` ranks classifiers across data sets).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from touchbench.app.errors import FieldError
from touchbench.app.schemas.runs import BesideSchema, BesideTest
from touchbench.app.services.imported import is_imported
from touchbench.app.store.runs import RunInfo
from touchbench.benchmark.results import TaskKey, TaskResult

#: The t-test group of the leaderboard's own run.
OWN = "own"


@dataclass(frozen=True)
class Beside:
    """A run shown beside another, and how the two are compared.

    Attributes
    ----------
    run : RunInfo
    test : {"paired", "by fold number", "means"}
    note : str
        Why, in a sentence.
    names : dict of str to str
        The run's classifier ids -> the names its rows have on the leaderboard.
    """

    run: RunInfo
    test: BesideTest
    note: str
    names: dict[str, str]

    @property
    def group(self) -> str:
        """The leaderboard's t-test group of this run's classifiers."""
        return OWN if self.test != "means" else f"run {self.run.id}"

    def schema(self) -> BesideSchema:
        return BesideSchema(
            run_id=self.run.id,
            name=self.run.config.name,
            origin="imported" if is_imported(self.run) else "touchbench",
            folds=self.run.fold_scheme,
            n_folds=_folds(self.run),
            n_repeats=_repeats(self.run),
            test=self.test,
            note=self.note,
            classifiers=self.names,
        )


def pairing(run: RunInfo, other: RunInfo) -> tuple[BesideTest, str]:
    """How ``other``'s classifiers compare with ``run``'s (see the module's notes).

    Raises
    ------
    FieldError
        ``other`` is on another data set or target, or is not a multi-class run.
    """
    if other.dataset_id != run.dataset_id or other.targets != run.targets:
        raise FieldError(
            "beside",
            f"run {other.id} is on {other.dataset_name} ({', '.join(other.targets)}) and "
            f"run {run.id} on {run.dataset_name} ({', '.join(run.targets)}): only runs of "
            "one data set and target rank side by side",
        )
    if other.kind != run.kind:
        raise FieldError("beside", f"run {other.id} is {other.kind} and run {run.id} {run.kind}")
    shape = (_folds(run), _repeats(run))
    other_shape = (_folds(other), _repeats(other))
    if shape != other_shape:
        return "means", (
            f"means only: run {other.id} has {other_shape[0]} folds x {other_shape[1]} and "
            f"run {run.id} {shape[0]} x {shape[1]}, so no folds pair"
        )
    ours = not is_imported(run) and not is_imported(other)
    same = [(c.fold_scheme, c.seed, c.n_instances) for c in (run.config, other.config)]
    if ours and same[0] == same[1]:
        return "paired", "the same folds (same data set, fold scheme, k, repeats and seed)"
    return "by fold number", (
        f"corrected t-test with folds paired by number: same data set, target, "
        f"{shape[0]} folds x {shape[1]}, but other fold assignments "
        f"({other.fold_scheme} against {run.fold_scheme}), so not the same test instances: "
        "an approximation of a paired test"
    )


def besides(run: RunInfo, others: Sequence[RunInfo]) -> list[Beside]:
    """Each of ``others`` with its pairing and its classifiers' names on ``run``'s board
    (``ID@run N`` where an id is taken already)."""
    taken = set(run.classifiers)
    out = []
    for other in others:
        if other.id == run.id:
            raise FieldError("beside", f"run {other.id} is the leaderboard's own run")
        test, note = pairing(run, other)
        names = {}
        for classifier in other.classifiers:
            name = classifier if classifier not in taken else f"{classifier}@run{other.id}"
            taken.add(name)
            names[classifier] = name
        out.append(Beside(other, test, note, names))
    return out


def merged_results(
    results: Sequence[TaskResult],
    others: Sequence[tuple[Beside, Sequence[TaskResult]]],
) -> tuple[list[TaskResult], dict[str, str]]:
    """``results`` and the other runs' results under their leaderboard names, and the
    t-test group of every classifier (see :func:`benchmark.evaluation.leaderboard.
    build_leaderboard`)."""
    merged = list(results)
    groups = {r.key.classifier: OWN for r in results}
    for beside, theirs in others:
        for result in theirs:
            name = beside.names.get(result.key.classifier, result.key.classifier)
            merged.append(_renamed(result, name))
            groups[name] = beside.group
    return merged, groups


def row_runs(besides_: Sequence[Beside]) -> Mapping[str, int]:
    """Leaderboard name -> the run beside it comes from."""
    return {name: b.run.id for b in besides_ for name in b.names.values()}


def _renamed(result: TaskResult, name: str) -> TaskResult:
    if name == result.key.classifier:
        return result
    fields: dict[str, Any] = dict(result.__dict__)
    fields["key"] = TaskKey(name, result.key.repeat, result.key.fold)
    return TaskResult(**fields)


def _folds(run: RunInfo) -> int:
    return run.config.folds or 1


def _repeats(run: RunInfo) -> int:
    return run.config.repeats or 1
