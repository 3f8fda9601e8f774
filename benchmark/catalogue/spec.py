"""The record that describes one classifier configuration of the catalogue."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Literal

from sklearn.base import BaseEstimator

Cost = Literal["fast", "slow"]
Scaling = Literal["standard", "minmax"]


@dataclass(frozen=True)
class ClassifierSpec:
    """One classifier configuration, as data.

    Parameters
    ----------
    id : str
        Short, lower-case, stable identifier (``"rf"``, ``"svm-rbf"``).
    weka_name : str or None
        The WEKA class it corresponds to, if one does.
    family : str
        The kind of model (``"trees"``, ``"svm"``, ``"naive-bayes"``...).
    description : str
        One line for listings.
    factory : callable
        Builds the unfitted estimator from ``params``; a class or a module-level function,
        so that the spec pickles by reference into worker processes.
    params : mapping of str to Any
        Keyword arguments of ``factory``.
    probabilities : bool
        Whether the estimator has ``predict_proba``.
    needs_scaling : bool
        Whether numeric features are scaled in the pipeline (see ``scaling``).
    handles_missing : bool
        Whether the estimator takes NaN itself, so that the pipeline does not impute.
    handles_nominal : bool
        Whether the estimator takes nominal codes natively (given through its
        ``categorical_features`` parameter) instead of one-hot columns.
    cost : {"fast", "slow"}
        Rough cost: ``"slow"`` means more than about 5 s per fold on a few thousand
        instances and a hundred features, single-threaded.
    suites : frozenset of str
        The suites it belongs to besides ``"all"``: ``"fast"``, ``"default"``.
    limits : str
        Known limits and differences from the WEKA counterpart.
    scaling : {"standard", "minmax"}
        The scaler used when ``needs_scaling``.
    """

    id: str
    weka_name: str | None
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

    def make_estimator(self) -> BaseEstimator:
        """A new unfitted estimator built from ``factory(**params)``."""
        return self.factory(**self.params)

    def to_json(self) -> dict[str, Any]:
        """The spec as JSON-ready data (the factory as its qualified name)."""
        return {
            "id": self.id,
            "weka_name": self.weka_name,
            "family": self.family,
            "description": self.description,
            "estimator": f"{self.factory.__module__}.{self.factory.__qualname__}",
            "params": {name: _jsonable(value) for name, value in self.params.items()},
            "probabilities": self.probabilities,
            "needs_scaling": self.needs_scaling,
            "scaling": self.scaling if self.needs_scaling else None,
            "handles_missing": self.handles_missing,
            "handles_nominal": self.handles_nominal,
            "cost": self.cost,
            "suites": sorted(self.suites | {"all"}),
            "limits": self.limits,
        }


def _jsonable(value: Any) -> Any:
    if value is None or isinstance(value, bool | int | float | str):
        return value
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    return repr(value)
