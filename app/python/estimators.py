"""A researcher's own scikit-learn estimators as classifiers of a run, beside catalogue ids.

An estimator object becomes a :class:`~benchmark.catalogue.spec.ClassifierSpec` whose
factory rebuilds a clone of it in the engine's worker processes.  The object is carried
there by value with cloudpickle (a class written in a notebook lives in no importable
module, so plain pickle's reference would not find it); it goes from this process to the
workers it starts, never through the store, which keeps only the entry's id.  The
pipeline imputes missing values and one-hot encodes nominal features before it, and
leaves scaling to the estimator (a ``Pipeline`` of the caller's own does it if wanted).
"""

from __future__ import annotations

# Imports inside functions: start-up time: cloudpickle and scikit-learn load with the first
# estimator of the caller's own.
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from touchbench.app.errors import FieldError

if TYPE_CHECKING:
    from touchbench.benchmark.catalogue import ClassifierSpec

#: What ``classifiers`` may hold besides ids: an estimator, or a (name, estimator) pair.
Classifier = Any


def rebuilt(blob: bytes) -> Any:
    """A fresh clone of the estimator pickled in ``blob`` (the spec's factory, run in the
    engine's worker processes)."""
    import cloudpickle
    from sklearn.base import clone

    return clone(cloudpickle.loads(blob))


def classifier_choice(
    classifiers: str | Sequence[Classifier],
) -> tuple[str | None, list[str], dict[str, ClassifierSpec]]:
    """``classifiers`` as a request names them, and the specs of the estimators among them.

    Parameters
    ----------
    classifiers : str or sequence
        A suite name (``fast``, ``default``, ``all``), or a list mixing catalogue ids,
        estimator objects (named by their class) and ``(name, estimator)`` pairs.

    Returns
    -------
    suite : str or None
    ids : list of str
        Every classifier's id, in the order given.
    specs : dict of str to ClassifierSpec
        The estimators' specs, by id.

    Raises
    ------
    FieldError
        For ``classifiers``: something that is neither an id nor an estimator, an
        estimator without ``fit``/``predict``, two classifiers with the same name.
    """
    if isinstance(classifiers, str):
        return classifiers, [], {}
    ids: list[str] = []
    specs: dict[str, ClassifierSpec] = {}
    for item in classifiers:
        if isinstance(item, str):
            name = item
        else:
            name, estimator = _named(item)
            specs[name] = estimator_spec(name, estimator)
        if name in ids:
            raise FieldError(
                "classifiers",
                f"two classifiers are named '{name}': give one a name of its own with a "
                "(name, estimator) pair",
            )
        ids.append(name)
    if not ids:
        raise FieldError("classifiers", "is empty: name a suite or at least one classifier")
    return None, ids, specs


def estimator_spec(name: str, estimator: Any) -> ClassifierSpec:
    """The catalogue spec of a scikit-learn estimator, called ``name``."""
    import cloudpickle

    from touchbench.benchmark.catalogue import ClassifierSpec

    try:
        blob = cloudpickle.dumps(estimator)
    except Exception as error:
        raise FieldError(
            "classifiers", f"estimator '{name}' cannot be sent to the worker processes: {error}"
        ) from None
    return ClassifierSpec(
        id=name,
        weka_command=None,
        family="own",
        description=f"{type(estimator).__name__}, the caller's own estimator",
        factory=rebuilt,
        params={"blob": blob},
        probabilities=hasattr(estimator, "predict_proba"),
        needs_scaling=False,
        handles_missing=False,
        handles_nominal=False,
        cost="fast",
        suites=frozenset(),
    )


def _named(item: Any) -> tuple[str, Any]:
    if isinstance(item, tuple):
        if len(item) != 2 or not isinstance(item[0], str) or not item[0]:
            raise FieldError("classifiers", "a pair must be (name, estimator)")
        name, estimator = item
    else:
        name, estimator = type(item).__name__, item
    if not (hasattr(estimator, "fit") and hasattr(estimator, "predict")):
        raise FieldError(
            "classifiers",
            f"'{name}' ({type(estimator).__name__}) is neither a classifier id nor an "
            "estimator with fit and predict",
        )
    if not hasattr(estimator, "get_params"):
        raise FieldError(
            "classifiers", f"'{name}' is not a scikit-learn estimator (it has no get_params)"
        )
    return name, estimator
