"""The record that describes one classifier configuration of the catalogue."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Literal

from sklearn.base import BaseEstimator

from touchbench.benchmark.extras import missing

Cost = Literal["fast", "slow"]
Scaling = Literal["standard", "minmax"]
#: How an ensemble's members' predictions make its own: ``soft`` the mean of their class
#: probabilities, ``hard`` the majority of their labels (scikit-learn's VotingClassifier
#: either way), ``selection`` Caruana's greedy ensemble selection with replacement.
Combine = Literal["soft", "hard", "selection"]

#: Estimator parameter (as ``get_params(deep=True)`` names it) to the values to try.
SearchSpace = Mapping[str, tuple[Any, ...]]


@dataclass(frozen=True)
class Tuning:
    """How a tuned twin is made: its entry's search space, searched within each training fold.

    Parameters
    ----------
    base : ClassifierSpec
        The entry tuned (its ``search_space`` is searched).
    budget_minutes : float or None
        Minutes the search may plan for in one training fold; ``None``: about
        :data:`benchmark.catalogue.tuning.DEFAULT_FITS` fits of the default setting.
    """

    base: ClassifierSpec
    budget_minutes: float | None = None


@dataclass(frozen=True)
class Stacking:
    """How a stack is made: the members it may choose from and how many it keeps.

    Parameters
    ----------
    members : tuple of ClassifierSpec
        Candidates; each training fold keeps the ``top_n`` best by inner cross-validation.
    top_n : int
    """

    members: tuple[ClassifierSpec, ...]
    top_n: int


@dataclass(frozen=True)
class Ensemble:
    """How an ensemble of catalogue entries is made: the entries it combines, and how.

    In a run, an ensemble is computed from its members' fold predictions (each member
    fitted once per fold, and shared with the run's other entries and ensembles); on its
    own (a model trained on all the data, a multi-target base) it fits its members itself.

    Parameters
    ----------
    members : tuple of ClassifierSpec
        The entries combined, each with its own preprocessing.
    combine : {"soft", "hard", "selection"}
        ``soft``: the mean of the members' class probabilities, its most probable class the
        prediction; ``hard``: the most frequent of their labels (ties: the lowest code);
        ``selection``: in each training fold, ``rounds`` rounds of Caruana's greedy
        selection with replacement on the members' inner out-of-fold predictions
        (:mod:`benchmark.catalogue.ensembles`), a weighted mean of the chosen.
    rounds : int
        ``selection`` only: rounds of the greedy selection.
    """

    members: tuple[ClassifierSpec, ...]
    combine: Combine
    rounds: int = 0

    @property
    def ids(self) -> tuple[str, ...]:
        """The members' ids, in order."""
        return tuple(member.id for member in self.members)


@dataclass(frozen=True)
class ClassifierSpec:
    """One classifier configuration, as data.

    Parameters
    ----------
    id : str
        Short, lower-case, stable identifier (``"rf"``, ``"svm-rbf"``).
    weka_command : str or None
        The WEKA command line (class, then options as WEKA writes them) whose behaviour
        and defaults this entry reproduces, checked against WEKA itself
        (``perf/weka_agreement.py``); ``None`` when no WEKA scheme computes the same.
    family : str
        The kind of model (``"trees"``, ``"svm"``, ``"naive-bayes"``...).
    description : str
        One line for listings.
    factory : callable
        Builds the unfitted estimator from ``params`` (and, for an ensemble, its members'
        estimators); a class or a module-level function, so that the spec pickles by
        reference into worker processes.
    params : mapping of str to Any
        Keyword arguments of ``factory``.
    probabilities : bool
        Whether the estimator has ``predict_proba``.
    needs_scaling : bool
        Whether numeric features are scaled in the pipeline (see ``scaling``).
    handles_missing : bool
        Whether the estimator takes NaN itself, so that the pipeline does not impute.
    handles_nominal : bool
        Whether the estimator takes nominal codes natively instead of one-hot columns:
        their positions go to its ``nominal_features`` parameter (position to number of
        labels) or, failing that, to its ``categorical_features`` parameter (positions).
    cost : {"fast", "slow"}
        Rough cost: ``"slow"`` means more than about 5 s per fold on a few thousand
        instances and a hundred features, single-threaded.
    suites : frozenset of str
        The suites it belongs to besides ``"all"``: ``"fast"``, ``"default"``.
    limits : str
        Known limits and differences from the WEKA counterpart.
    scaling : {"standard", "minmax"}
        The scaler used when ``needs_scaling``.
    min_sequence : int or None
        ``None`` for a classifier of flat feature vectors; otherwise it reads a sequence
        data set's windows (:mod:`benchmark.sequence`) through its ``sequence`` parameter,
        and needs at least this many time steps per channel.
    search_space : mapping of str to tuple, or None
        Values to try per estimator parameter (names as the estimator's
        ``get_params(deep=True)`` gives them), for ``bench --tune``
        (:mod:`benchmark.catalogue.spaces`).
    tuning : Tuning or None
        Set on a tuned twin (``rf+tuned``): the pipeline searches ``tuning.base``'s space.
    stacking : Stacking or None
        Set on a stack (``stack-top3``, ``stacking``): the pipeline stacks the best of its
        members.
    ensemble : Ensemble or None
        Set on an ensemble of entries (``voting``, ``voting-hard``, ``ensemble-5``): the
        entries it combines, and how.
    """

    id: str
    weka_command: str | None
    family: str
    description: str
    factory: Callable[..., BaseEstimator]
    params: Mapping[str, Any]
    probabilities: bool
    needs_scaling: bool
    handles_missing: bool
    handles_nominal: bool
    cost: Cost
    suites: frozenset[str]
    limits: str = ""
    scaling: Scaling = "standard"
    min_sequence: int | None = None
    search_space: SearchSpace | None = None
    tuning: Tuning | None = None
    stacking: Stacking | None = None
    ensemble: Ensemble | None = None

    @property
    def members(self) -> tuple[ClassifierSpec, ...]:
        """The entries a stack or an ensemble combines (none for any other entry)."""
        if self.stacking is not None:
            return self.stacking.members
        return self.ensemble.members if self.ensemble is not None else ()

    @property
    def requires(self) -> tuple[str, ...]:
        """The optional modules it needs (:mod:`benchmark.extras`): its factory's
        ``REQUIRES`` and those of the entries it is made of."""
        parts = [*getattr(self.factory, "REQUIRES", ())]
        if self.tuning is not None:
            parts += self.tuning.base.requires
        for member in self.members:
            parts += member.requires
        return tuple(dict.fromkeys(parts))

    @property
    def installed(self) -> bool:
        """Whether every optional module it needs is installed."""
        return not missing(self.requires)

    @property
    def needs_sequence(self) -> bool:
        """Whether it only works on a sequence data set."""
        return self.min_sequence is not None

    @property
    def weka_name(self) -> str | None:
        """The WEKA class of ``weka_command`` (``"weka.classifiers.trees.J48"``), if any."""
        return self.weka_command.split(maxsplit=1)[0] if self.weka_command else None

    @property
    def weka_options(self) -> str:
        """The options of ``weka_command`` (``"-C 0.25 -M 2"``), empty without one."""
        parts = (self.weka_command or "").split(maxsplit=1)
        return parts[1] if len(parts) > 1 else ""

    def make_estimator(self) -> BaseEstimator:
        """A new unfitted estimator built from ``factory(**params)``; an ensemble's factory
        takes its members' (name, estimator) pairs as ``members`` too."""
        if self.ensemble is not None:
            members = [(member.id, member.make_estimator()) for member in self.ensemble.members]
            return self.factory(members=members, **self.params)
        return self.factory(**self.params)

    def to_json(self) -> dict[str, Any]:
        """The spec as JSON-ready data (the factory as its qualified name)."""
        return {
            "id": self.id,
            "weka_name": self.weka_name,
            "weka_command": self.weka_command,
            "family": self.family,
            "description": self.description,
            "estimator": f"{self.factory.__module__}.{self.factory.__qualname__}",
            "params": {name: jsonable(value) for name, value in self.params.items()},
            "probabilities": self.probabilities,
            "needs_scaling": self.needs_scaling,
            "scaling": self.scaling if self.needs_scaling else None,
            "handles_missing": self.handles_missing,
            "handles_nominal": self.handles_nominal,
            "cost": self.cost,
            "suites": sorted(self.suites | {"all"}),
            "limits": self.limits,
            "requires": list(self.requires),
            "installed": self.installed,
            "min_sequence": self.min_sequence,
            "search_space": None
            if self.search_space is None
            else {name: jsonable(values) for name, values in self.search_space.items()},
            "members": [member.id for member in self.members] or None,
            "combine": self.combine,
        }

    @property
    def combine(self) -> str | None:
        """How a stack or an ensemble combines its members: ``"stack"`` (a logistic
        regression over their inner out-of-fold class scores), ``"soft"``, ``"hard"`` or
        ``"selection"``; ``None`` for any other entry."""
        if self.stacking is not None:
            return "stack"
        return self.ensemble.combine if self.ensemble is not None else None


def make_spec(
    id: str,
    factory: Callable[..., BaseEstimator],
    params: Mapping[str, Any],
    *,
    family: str,
    description: str,
    weka_command: str | None = None,
    probabilities: bool = True,
    scaling: str | None = None,
    missing: bool = False,
    nominal: bool = False,
    cost: str = "fast",
    suites: frozenset[str] = frozenset({"default"}),
    limits: str = "",
    min_sequence: int | None = None,
    ensemble: Ensemble | None = None,
) -> ClassifierSpec:
    """A :class:`ClassifierSpec` as catalogues declare it: ``scaling`` names the scaler
    (``None``: no scaling), ``missing`` and ``nominal`` what the estimator takes itself."""
    return ClassifierSpec(
        id=id,
        weka_command=weka_command,
        family=family,
        description=description,
        factory=factory,
        params=params,
        probabilities=probabilities,
        needs_scaling=scaling is not None,
        handles_missing=missing,
        handles_nominal=nominal,
        cost=cost,  # type: ignore[arg-type]
        suites=suites,
        limits=limits,
        scaling=scaling or "standard",  # type: ignore[arg-type]
        min_sequence=min_sequence,
        ensemble=ensemble,
    )


def jsonable(value: Any) -> Any:
    """``value`` as JSON holds it: numbers, strings and lists as they are (numpy scalars as
    Python ones), anything else as its ``repr``."""
    if value is None or isinstance(value, bool | int | float | str):
        return value
    if hasattr(value, "item") and getattr(value, "ndim", None) == 0:  # numpy scalars
        return jsonable(value.item())
    if isinstance(value, list | tuple):
        return [jsonable(v) for v in value]
    return repr(value)
