"""Which entries of a run are computed from others' fold predictions, and what they need.

A run's ensembles of entries (``voting``, ``voting-hard``), its stacks (``stacking``,
``stack-top3``) and its ensemble selection (``ensemble-5``) fit nothing themselves: the
engine computes each of their folds from their members' fold predictions
(:mod:`benchmark.run.combine`).  :func:`plan_run` says, before anything runs:

- the run's *workers*, the entries that are fitted (one task per fold), and its *derived*
  entries, members before the entries made of them;
- the *helpers*: members no one asked for, fitted once per fold and shared by every entry
  that names them, listed with the run's entries so that their cost shows;
- the entries whose tasks must also predict their training fold out of fold on the run's
  inner folds (:mod:`benchmark.catalogue.inner`): the candidates of a stack or of the
  ensemble selection (a vote among them: its members), once for all of them.

A stack or a selection cannot itself be a candidate of another (its inner predictions would
need inner folds of the inner folds); such a candidate is left out, and the plan says so.
Only multi-class runs have derived entries: a multi-target configuration or a regressor
fits its ensemble itself.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field

from touchbench.benchmark.catalogue import ClassifierSpec, check_sequence_input
from touchbench.benchmark.catalogue.ensembles import selection_id, selection_spec
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.estimators import check_classifier
from touchbench.benchmark.extras import require
from touchbench.benchmark.problem import Problem
from touchbench.benchmark.results import Origin, TaskKey, TaskResult
from touchbench.benchmark.sequence import SequenceLayout

__all__ = ["Derived", "RunPlan", "plan_run"]

#: How a derived entry combines its members (:attr:`ClassifierSpec.combine`).
VOTES = frozenset({"soft", "hard"})


@dataclass(frozen=True)
class Derived:
    """An entry computed from other entries' fold predictions.

    Attributes
    ----------
    id : str
    spec : ClassifierSpec
    members : tuple of str
        The entries it combines (workers or votes), in the spec's order; for a stack or a
        selection, its candidates that can take part.
    combine : {"soft", "hard", "stack", "selection"}
    left_out : dict of str to str
        Candidates of a stack or selection that cannot take part, and why.
    """

    id: str
    spec: ClassifierSpec
    members: tuple[str, ...]
    combine: str
    left_out: Mapping[str, str] = field(default_factory=dict)

    @property
    def reads_inner(self) -> bool:
        """Whether it reads its members' inner out-of-fold predictions (a stack, a
        selection)."""
        return self.combine not in VOTES


@dataclass(frozen=True)
class RunPlan:
    """What a run fits and what it computes from fold predictions.

    Attributes
    ----------
    entries : tuple of str
        Every entry with results: the run's, then its helpers.
    helpers : tuple of str
        Members that the run did not ask for.
    specs : dict of str to ClassifierSpec
        Every multi-class spec a worker or a derived entry needs (extra specs included).
    derived : dict of str to Derived
        In an order where an entry's members come before it.
    inner : frozenset of str
        Entries whose inner out-of-fold predictions a stack or selection reads: workers,
        whose tasks predict their training fold out of fold, and votes, computed from
        their members' inner predictions.
    """

    entries: tuple[str, ...]
    helpers: tuple[str, ...]
    specs: dict[str, ClassifierSpec]
    derived: dict[str, Derived]
    inner: frozenset[str]

    @property
    def workers(self) -> tuple[str, ...]:
        """The entries that are fitted, one task per fold, in :attr:`entries`' order."""
        return tuple(entry for entry in self.entries if entry not in self.derived)

    def origins(self) -> dict[str, Origin]:
        """How the run comes by the folds of its derived entries and helpers, for the
        leaderboard (:func:`benchmark.evaluation.leaderboard.build_leaderboard`)."""
        origins = {
            name: Origin("from fold predictions", derived.members)
            for name, derived in self.derived.items()
        }
        for helper in self.helpers:
            if helper in origins:
                continue  # a derived entry no one asked for: its members say more
            users = tuple(n for n, d in self.derived.items() if helper in d.members)
            origins[helper] = Origin("helper", users)
        return origins

    def needs(self, entry: str) -> frozenset[str]:
        """The workers whose folds ``entry``'s fold is computed from (itself for a worker)."""
        if entry not in self.derived:
            return frozenset({entry})
        return frozenset().union(*(self.needs(m) for m in self.derived[entry].members))

    def uses(self, entry: str) -> frozenset[str]:
        """Every entry whose folds ``entry``'s fold is computed from: its members, theirs..."""
        derived = self.derived.get(entry)
        if derived is None:
            return frozenset()
        return frozenset(derived.members).union(*(self.uses(m) for m in derived.members))

    def needs_inner(self, entry: str) -> frozenset[str]:
        """The workers whose inner predictions ``entry``'s fold reads."""
        derived = self.derived.get(entry)
        if derived is None or not derived.reads_inner:
            return frozenset()
        return frozenset().union(*(self.needs(m) for m in derived.members))

    def reruns(
        self,
        rounds: Sequence[tuple[int, int]],
        done: Collection[TaskKey],
        previous: Mapping[TaskKey, TaskResult],
    ) -> set[TaskKey]:
        """Tasks done by an earlier execution of the run that must run again, quietly:
        their predictions are needed by a derived entry's fold still to compute and are
        not at hand (results read back from a store that does not keep them)."""
        again = set()
        for repeat, fold in rounds:
            for entry in self.derived:
                if TaskKey(entry, repeat, fold) in done:
                    continue
                inner = self.needs_inner(entry)
                for worker in self.needs(entry):
                    key = TaskKey(worker, repeat, fold)
                    if key not in done:
                        continue
                    result = previous.get(key)
                    if result is None or (
                        result.ok
                        and (
                            result.predictions is None
                            or (worker in inner and result.inner_predictions is None)
                        )
                    ):
                        again.add(key)
        return again


def plan_run(
    problem: Problem,
    classifiers: Sequence[str],
    *,
    extra_specs: Mapping[str, ClassifierSpec] | None = None,
    ensemble: int | None = None,
) -> RunPlan:
    """Check a run's classifier ids and plan its workers, helpers and derived entries.

    Parameters
    ----------
    problem : Problem
    classifiers : sequence of str
        The run's ids (duplicates ignored); may hold ``ensemble-N`` when ``ensemble`` is N.
    extra_specs : mapping of str to ClassifierSpec, optional
        Multi-class specs outside the catalogue (a run's stack, WEKA commands...).
    ensemble : int, optional
        Add ``ensemble-N``: Caruana's ensemble selection of N rounds over the run's entries.

    Raises
    ------
    ConfigurationError
        No classifiers; an unknown or unfitting id; ``ensemble`` on a run that is not
        multi-class, out of range, or without an entry to choose from; members that make a
        cycle.
    """
    ids = list(dict.fromkeys(classifiers))
    if not ids:
        raise ConfigurationError("no classifiers to run")
    extras: dict[str, ClassifierSpec] = dict(extra_specs or {})
    chosen = None
    if ensemble is not None:
        if problem.kind != "multiclass":
            raise ConfigurationError(
                "an ensemble selection combines multi-class classifiers: pick one target"
            )
        chosen = selection_id(ensemble)
        ids = [i for i in ids if i != chosen]
    specs: dict[str, ClassifierSpec] = dict(extras)
    for classifier in ids:
        spec = check_classifier(classifier, problem, extras)
        if spec is not None:
            specs[classifier] = spec
    if problem.kind != "multiclass":
        return RunPlan(tuple(ids), (), specs, {}, frozenset())
    if chosen is not None and ensemble is not None:
        candidates = [specs[i] for i in ids if _can_be_candidate(specs[i])]
        specs[chosen] = selection_spec(candidates, ensemble)
        ids.append(chosen)
    return _Planner(ids, specs, problem.sequence).plan()


def _can_be_candidate(spec: ClassifierSpec) -> bool:
    """Whether inner predictions of ``spec`` follow from its members' (a worker, a vote)."""
    return spec.combine is None or spec.combine in VOTES


class _Planner:
    """Resolves the members of a run's derived entries into workers and helpers."""

    def __init__(
        self, ids: list[str], specs: dict[str, ClassifierSpec], sequence: SequenceLayout | None
    ) -> None:
        self.asked = ids
        self.sequence = sequence
        self.specs = specs
        self.helpers: list[str] = []
        self.derived: dict[str, Derived] = {}
        self.inner: set[str] = set()
        self._visiting: set[str] = set()

    def plan(self) -> RunPlan:
        for entry in self.asked:
            self._visit(entry)
        for derived in list(self.derived.values()):
            if derived.reads_inner:
                for member in derived.members:
                    self._mark_inner(member)
        return RunPlan(
            tuple(self.asked + self.helpers),
            tuple(self.helpers),
            self.specs,
            self.derived,
            frozenset(self.inner),
        )

    def _visit(self, entry: str) -> None:
        """Plan ``entry`` after its members (depth first), helpers added as met."""
        spec = self.specs[entry]
        if spec.combine is None or entry in self.derived:
            return
        if entry in self._visiting:
            raise ConfigurationError(f"'{entry}' is among its own members")
        self._visiting.add(entry)
        members, left_out = [], {}
        for member in spec.members:
            if member.id not in self.specs:
                require(member.requires, f"classifier '{entry}'")
                self.specs[member.id] = member
                self.helpers.append(member.id)
            known = self.specs[member.id]
            check_sequence_input(known, self.sequence)
            if spec.combine in VOTES or _can_be_candidate(known):
                members.append(member.id)
                self._visit(member.id)
            else:
                left_out[member.id] = (
                    "a stack or selection has no inner predictions to choose it by"
                )
        self._visiting.discard(entry)
        self.derived[entry] = Derived(entry, spec, tuple(members), spec.combine or "", left_out)

    def _mark_inner(self, entry: str) -> None:
        self.inner.add(entry)
        derived = self.derived.get(entry)
        for member in derived.members if derived is not None else ():
            self._mark_inner(member)
