"""Tuned twins of catalogue entries: successive halving inside each training fold.

``rf+tuned`` is ``rf`` whose parameters are chosen, in every outer training fold, by
scikit-learn's successive halving search with an inner cross-validation of that fold
only: nested cross-validation, so the outer test fold never takes part in the choice.

The plan. Successive halving (``factor`` 3) starts all candidates on a small sample of the
training rows and keeps the best third on three times the rows; the rounds end with
``factor`` candidates on a ``factor``-th of the rows (:func:`schedule`: scikit-learn's
``"exhaust"`` plan would go on with one candidate on all the rows, a round that chooses
nothing). Its cost is estimated before it starts, from two timed fits and predictions of
the default setting (on a 27th and a ninth of the rows: ``a + b * rows`` seconds), two
random settings of the space timed against the default, and what the search itself
spends on each candidate and inner fold besides the estimator (cloning, splitting,
scoring, bookkeeping: measured once per process, see :func:`evaluation_overhead`), which
dominates for the cheapest estimators. The first round gets the most candidates (3, 9,
27, ...) whose estimated search, plus the timing fits and the final refit, fits the
budget: by default :data:`DEFAULT_FITS` fits of the default setting on all the training
rows, or a number of minutes per outer fold (``bench --budget``). The spaces
(:mod:`benchmark.catalogue.spaces`) hold no setting that costs much more than the
default, since even the fewest candidates (3) and the refit of the chosen one must fit.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping
from dataclasses import replace
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin, clone
from sklearn.experimental import enable_halving_search_cv  # noqa: F401 (enables the import)
from sklearn.model_selection import (
    HalvingGridSearchCV,
    HalvingRandomSearchCV,
    ParameterGrid,
    StratifiedKFold,
)
from sklearn.utils.metaestimators import available_if

from touchbench.benchmark.catalogue.inner import INNER_FOLDS, inner_folds
from touchbench.benchmark.catalogue.spec import ClassifierSpec, SearchSpace, Tuning
from touchbench.benchmark.errors import ConfigurationError

#: Suffix of a tuned twin's id: ``rf+tuned``.
TUNED_SUFFIX = "+tuned"
#: The default budget, in fits of the default setting on all the training rows.
DEFAULT_FITS = 6.0
#: Most candidates a budget may buy.
MAX_CANDIDATES = 729
#: Largest budget accepted, in minutes (per tuned entry and outer fold).
MAX_BUDGET_MINUTES = 1440.0
#: Least cost of the space's settings assumed, as a multiple of the default's: cheaper
#: settings are not counted cheaper (two timed draws are too few to trust a saving, and a
#: plan that buys 81 candidates on one amplifies its error), dearer ones are.
MIN_RATIO = 1.0
#: Step of the pipeline a space's parameters belong to.
CLASSIFIER_STEP = "classifier"


def tuned_id(classifier_id: str) -> str:
    """``"rf"`` -> ``"rf+tuned"``."""
    return classifier_id + TUNED_SUFFIX


def is_tuned_id(classifier_id: str) -> bool:
    """Whether ``classifier_id`` names a tuned twin."""
    return classifier_id.endswith(TUNED_SUFFIX)


def check_budget(budget_minutes: float | None) -> None:
    """Refuse a budget outside (0, :data:`MAX_BUDGET_MINUTES`] minutes."""
    if budget_minutes is None:
        return
    if not 0 < budget_minutes <= MAX_BUDGET_MINUTES:
        raise ConfigurationError(
            f"`budget` must be more than 0 and at most {MAX_BUDGET_MINUTES:g} minutes, "
            f"got {budget_minutes:g}"
        )


def check_search_space(spec: ClassifierSpec) -> None:
    """Refuse a search space that names a parameter the entry's estimator does not have.

    Raises
    ------
    ConfigurationError
        One line naming the entry, the parameter and the closest parameters it has, or an
        empty list of values.
    """
    if not spec.search_space:
        return
    estimator = spec.make_estimator()
    known = estimator.get_params(deep=True)
    for name, values in spec.search_space.items():
        if name not in known:
            import difflib

            close = difflib.get_close_matches(name, list(known), n=3, cutoff=0.5)
            hint = f"; did you mean {', '.join(close)}?" if close else ""
            raise ConfigurationError(
                f"search space of '{spec.id}' names '{name}', which "
                f"{type(estimator).__name__} does not have{hint}"
            )
        if len(tuple(values)) == 0:
            raise ConfigurationError(f"search space of '{spec.id}' gives no value for '{name}'")


def tuned_spec(spec: ClassifierSpec, budget_minutes: float | None = None) -> ClassifierSpec:
    """The tuned twin of an entry that declares a search space.

    Raises
    ------
    ConfigurationError
        The entry has no search space, its space names a parameter its estimator lacks,
        or the budget is out of range.
    """
    if not spec.search_space:
        raise ConfigurationError(
            f"classifier '{spec.id}' declares no search space, so it has no tuned twin "
            "(the classifier listing gives each entry's search space)"
        )
    check_search_space(spec)
    check_budget(budget_minutes)
    size = len(ParameterGrid(as_grid(spec.search_space)))
    return replace(
        spec,
        id=tuned_id(spec.id),
        weka_command=None,
        description=f"{spec.description}; tuned in each training fold by successive "
        f"halving over {size} settings",
        cost="slow",
        suites=frozenset(),
        search_space=None,
        tuning=Tuning(spec, budget_minutes),
    )


def as_grid(space: SearchSpace, prefix: str = "") -> dict[str, list[Any]]:
    """A search space as scikit-learn's searches take it, each name after ``prefix``
    (``"classifier__"`` for the parameters of a catalogue pipeline's estimator)."""
    return {prefix + name: list(values) for name, values in space.items()}


class TunedClassifier(ClassifierMixin, BaseEstimator):
    """A classifier whose parameters successive halving chooses on its training data.

    Parameters
    ----------
    estimator : estimator
        The classifier (a pipeline) to tune; cloned, never fitted itself.
    space : mapping of str to sequence
        Parameter of ``estimator`` (``classifier__C``) to the values to try.
    budget : float or None
        Seconds the search may plan for; ``None`` for :data:`DEFAULT_FITS` default fits.
    cv : int
        Inner folds (:func:`benchmark.catalogue.inner.inner_folds`, the plan stacks and
        ensemble selection share).
    factor : int
        Halving factor: each round keeps a 1/factor of the candidates on factor x the rows.
    scoring : str
        scikit-learn scorer name of the inner cross-validation.
    random_state : int or None
        Seed of the inner folds, the candidates drawn and the row samples.

    Attributes
    ----------
    best_params_ : dict
        The chosen setting, named as in the entry's search space.
    best_estimator_ : estimator
        ``estimator`` with ``best_params_``, refitted on all the training rows.
    n_candidates_ : int
        Settings of the first round.
    n_resources_ : int
        Rows (inner training and test folds together) of the last round (see
        :func:`schedule`).
    classes_ : ndarray of shape (n_classes,)
    """

    def __init__(
        self,
        estimator: Any = None,
        space: Mapping[str, Any] | None = None,
        budget: float | None = None,
        cv: int = INNER_FOLDS,
        factor: int = 3,
        scoring: str = "f1_weighted",
        random_state: int | None = None,
    ) -> None:
        self.estimator = estimator
        self.space = space
        self.budget = budget
        self.cv = cv
        self.factor = factor
        self.scoring = scoring
        self.random_state = random_state

    def fit(self, X: np.ndarray, y: np.ndarray) -> TunedClassifier:
        """Search the space with an inner cross-validation of ``(X, y)`` and refit the best.

        Parameters
        ----------
        X : ndarray of shape (n_samples, n_features)
        y : ndarray of shape (n_samples,)
        """
        y = np.asarray(y)
        grid = {name: list(values) for name, values in (self.space or {}).items()}
        size = len(ParameterGrid(grid))
        inner = inner_folds(y, self.cv, self.random_state)
        n_candidates = min(self._plan(X, y, grid, size), size)
        first, last = schedule(n_candidates, len(y), _smallest(y, self.cv), self.factor)
        common: dict[str, Any] = {
            "factor": self.factor,
            "min_resources": first,
            "max_resources": last,
            "cv": inner,
            "scoring": self.scoring,
            "random_state": self.random_state,
            "error_score": np.nan,
            "refit": True,
            # scoring the training rows too (the halving searches' default) costs a predict
            # of twice the rows and a second scoring, and nothing reads it
            "return_train_score": False,
        }
        search: Any
        if n_candidates >= size:
            search = HalvingGridSearchCV(clone(self.estimator), grid, **common)
        else:
            search = HalvingRandomSearchCV(
                clone(self.estimator), grid, n_candidates=n_candidates, **common
            )
        search.fit(X, y)
        # the search object itself is not kept: its scorer and splitter make a stored model
        # name types the model store does not trust, and it weighs more than the model
        self.best_estimator_ = search.best_estimator_
        self.best_params_ = {
            name.split("__", 1)[1] if name.startswith(CLASSIFIER_STEP + "__") else name: value
            for name, value in search.best_params_.items()
        }
        self.n_candidates_ = int(search.n_candidates_[0])
        self.n_resources_ = int(search.n_resources_[-1])
        self.classes_ = self.best_estimator_.classes_
        return self

    def _plan(self, X: np.ndarray, y: np.ndarray, grid: dict[str, list[Any]], size: int) -> int:
        """Candidates of the first round: the most (a power of ``factor``) whose estimated
        cost fits the budget, at least ``factor``.

        Costs are estimated as ``a + b * rows`` from two timed fits (and predictions) of
        the default setting, on a 27th and a ninth of the rows (see :func:`_fit_cost`),
        times the ratio of two random settings' cost to the default's on the ninth (fewer
        boosting rounds, more features per split), plus the search's own
        :func:`evaluation_overhead` per candidate and inner fold; the estimate counts the
        timing fits and the final refit too. The default budget is :data:`DEFAULT_FITS`
        fits of the default on all the rows.
        """
        n = len(y)
        started = time.perf_counter()
        cost, default = _fit_cost(self.estimator, X, y, self.random_state)
        budget = DEFAULT_FITS * default if self.budget is None else self.budget
        overhead = evaluation_overhead()
        smallest = _smallest(y, self.cv)

        def most(ratio: float, spent: float) -> int:
            chosen = self.factor
            while chosen < min(size, MAX_CANDIDATES):
                more = chosen * self.factor
                search = _search_cost(
                    more, n, smallest, self.factor, self.cv, lambda r: ratio * cost(r), overhead
                )
                if spent + search + ratio * cost(n) > budget:
                    break
                chosen = more
            return chosen

        # the settings' cost is timed only when it may change the plan: not when the
        # default's own cost buys no more than the fewest candidates (forests' fixed costs)
        if most(MIN_RATIO, time.perf_counter() - started) == self.factor:
            return self.factor
        ratio = _space_ratio(self.estimator, grid, X, y, self.random_state, cost)
        return most(ratio, time.perf_counter() - started)

    def predict(self, X: np.ndarray) -> np.ndarray:
        """Predictions of the refitted best setting, shape (n_samples,)."""
        return np.asarray(self.best_estimator_.predict(X))

    @available_if(lambda self: hasattr(_delegate(self), "predict_proba"))
    def predict_proba(self, X: np.ndarray) -> np.ndarray:
        """Class probabilities, shape (n_samples, n_classes)."""
        return np.asarray(self.best_estimator_.predict_proba(X))

    @available_if(lambda self: hasattr(_delegate(self), "decision_function"))
    def decision_function(self, X: np.ndarray) -> np.ndarray:
        """Decision values of the refitted best setting."""
        return np.asarray(self.best_estimator_.decision_function(X))


_OVERHEAD: list[float] = []


def evaluation_overhead() -> float:
    """Seconds a halving search spends per candidate and inner fold besides fitting and
    predicting: cloning, splitting, scoring, bookkeeping.

    Measured once per process, by a search of 3 candidates (12 fits and scores) over a
    classifier that costs nothing, on 270 synthetic rows of 3 classes: a few milliseconds,
    as much as a nearest-neighbour fit and predict on a few hundred rows.
    """
    if not _OVERHEAD:
        from sklearn.dummy import DummyClassifier

        rng = np.random.default_rng(0)
        X = rng.normal(size=(270, 4))
        y = np.arange(270) % 3
        search = HalvingGridSearchCV(
            DummyClassifier(strategy="stratified"),
            {"random_state": [0, 1, 2]},
            factor=3,
            cv=StratifiedKFold(3, shuffle=True, random_state=0),
            scoring="f1_weighted",
            min_resources="exhaust",
            refit=False,
            return_train_score=False,
        )
        started = time.perf_counter()
        search.fit(X, y)
        seconds = time.perf_counter() - started
        evaluations = 3 * sum(int(k) for k in search.n_candidates_)
        _OVERHEAD.append(seconds / evaluations)
    return _OVERHEAD[0]


def _delegate(tuned: TunedClassifier) -> Any:
    return getattr(tuned, "best_estimator_", tuned.estimator)


def _fit_cost(
    estimator: Any, X: np.ndarray, y: np.ndarray, seed: int | None
) -> tuple[Callable[[float], float], float]:
    """Seconds to fit ``estimator`` on so many rows and predict as many, ``a + b * rows``
    from two timed fits on a 27th and a ninth of the rows; and the default's cost on all
    the rows, the budget's unit: the smaller of that line's and of the power law's
    (``c * rows ** k``) through the same two points. The line overestimates it for the
    estimators whose fixed costs dominate small samples (boosting hundreds of rounds), and
    the budget must not grow with that error."""
    n = len(y)
    order = np.random.default_rng(seed).permutation(n)
    sizes = (max(n // 27, 10), max(n // 9, 20))
    seconds = []
    for rows in sizes:
        sample = order[: min(rows, n)]
        started = time.perf_counter()
        # scoring predicts too (it dominates for nearest neighbours): the sample itself
        clone(estimator).fit(X[sample], y[sample]).predict(X[sample])
        seconds.append(time.perf_counter() - started)
    slope = max((seconds[1] - seconds[0]) / max(sizes[1] - sizes[0], 1), 0.0)
    fixed = max(seconds[0] - slope * sizes[0], 0.0)
    whole = fixed + slope * n
    if seconds[0] > 0 and seconds[1] > seconds[0] and sizes[1] > sizes[0]:
        power = math.log(seconds[1] / seconds[0]) / math.log(sizes[1] / sizes[0])
        whole = min(whole, seconds[1] * (n / sizes[1]) ** power)
    return (lambda rows: fixed + slope * rows), whole


def _space_ratio(
    estimator: Any,
    grid: dict[str, list[Any]],
    X: np.ndarray,
    y: np.ndarray,
    seed: int | None,
    cost: Callable[[float], float],
    draws: int = 2,
) -> float:
    """Mean cost of ``draws`` random settings of ``grid`` over the default's (at least
    :data:`MIN_RATIO`), from fits and predictions on a ninth of the rows."""
    from sklearn.model_selection import ParameterSampler

    n = len(y)
    rows = max(n // 9, 20)
    sample = np.random.default_rng(seed).permutation(n)[: min(rows, n)]
    seconds = []
    for setting in ParameterSampler(grid, min(draws, len(ParameterGrid(grid))), random_state=seed):
        started = time.perf_counter()
        try:
            clone(estimator).set_params(**setting).fit(X[sample], y[sample]).predict(X[sample])
        except Exception:  # the search scores a failing setting NaN: it costs nothing here
            continue
        seconds.append(time.perf_counter() - started)
    if not seconds:
        return 1.0
    return max(float(np.mean(seconds)) / max(cost(rows), 1e-9), MIN_RATIO)


def schedule(n_candidates: int, n: int, smallest: int, factor: int) -> tuple[int, int]:
    """Rows of the first and the last round of a halving search of ``n_candidates``.

    scikit-learn's ``"exhaust"`` plan halves down to one candidate, which it then fits and
    scores on all ``n`` rows: a round that chooses nothing (the refit follows anyway), and
    the dearest. Here the rounds stop one earlier, with ``factor`` candidates on a
    ``factor``-th of the rows, which is where the exhaust plan makes its last choice too:
    the same choice for a third of the cost (``factor`` candidates: one round on a third of
    the rows). Too few rows for that: scikit-learn's own plan.

    Returns
    -------
    first, last : int
        ``min_resources`` and ``max_resources`` of the search.
    """
    required = 1 + math.floor(math.log(n_candidates, factor) + 1e-9)
    last = n // factor
    first = last // factor ** max(required - 2, 0)
    if required < 2 or first < smallest:
        return max(smallest, n // factor ** (required - 1)), n
    return first, last


def _smallest(y: np.ndarray, cv: int) -> int:
    """scikit-learn's ``"smallest"`` rows of a round: two per class and inner fold."""
    return 2 * cv * len(np.unique(y))


def _search_cost(
    n_candidates: int,
    n: int,
    smallest: int,
    factor: int,
    cv: int,
    cost: Callable[[float], float],
    overhead: float = 0.0,
) -> float:
    """Estimated seconds of a halving search on :func:`schedule`'s rounds, ``overhead``
    seconds added to each candidate's fit and score on each inner fold."""
    required = 1 + math.floor(math.log(n_candidates, factor) + 1e-9)
    first, last = schedule(n_candidates, n, smallest, factor)
    possible = 1 + math.floor(math.log(max(last // first, 1), factor) + 1e-9)
    total = 0.0
    for i in range(min(required, possible)):
        candidates = math.ceil(n_candidates / factor**i)
        rows = min(first * factor**i, last)
        total += cv * candidates * (overhead + cost(rows * (cv - 1) / cv))
    return total
