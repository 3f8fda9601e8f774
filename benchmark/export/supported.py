"""What exports to ONNX, and the one refusal of what does not."""

from __future__ import annotations

from typing import NoReturn

from sklearn.base import BaseEstimator

from touchbench.benchmark.catalogue.spec import ClassifierSpec
from touchbench.benchmark.errors import ConfigurationError

#: What the refusal says is supported.
SUPPORTED = (
    "scikit-learn's trees, forests, bagged trees, boosting, linear models, SVMs, "
    "naive Bayes, discriminant analysis, k-NN, MLPs, XGBoost, LightGBM and CatBoost, "
    "flat features; several targets: cr, cc, bcc, lc, ps and nsr over one of those"
)


def exports_onnx(spec: ClassifierSpec) -> bool:
    """Whether models of this catalogue entry export to ONNX (without fitting one)."""
    if spec.min_sequence is not None or spec.tuning is not None or spec.members:
        return False
    try:
        estimator = spec.make_estimator()
    except Exception:  # an entry that cannot even be built does not export
        return False
    return unsupported(estimator) is None


def unsupported(estimator: BaseEstimator, *, nested: bool = False) -> str | None:
    """Why ``estimator`` (fitted or not) has no converter that matches it, or None.

    ``nested``: inside another estimator, where the catalogue's wrappers of XGBoost,
    LightGBM and CatBoost are not unwrapped.
    """
    name = type(estimator).__name__
    inner = getattr(estimator, "estimator", None)
    if name == "LabelEncodedClassifier" and not nested:
        return None if type(inner).__name__ in ("XGBClassifier", "XGBRegressor") else name
    if name in WRAPPED_BOOSTERS and not nested:
        # onnxmltools writes a LightGBM random forest's probabilities with the wrong width
        return name if getattr(estimator, "boosting_type", "") == "rf" else None
    module = type(estimator).__module__
    if not module.startswith(("sklearn.", "xgboost.")) or name in _NO_CONVERTER:
        return name
    reason = _differs(estimator)
    if reason is not None:
        return reason
    if name == "Pipeline":
        steps = (unsupported(step, nested=True) for _, step in estimator.steps)
        return next(filter(None, steps), None)
    if inner is not None and not isinstance(inner, str):
        return unsupported(inner, nested=True)
    for _, member in getattr(estimator, "estimators", None) or ():
        reason = unsupported(member, nested=True)
        if reason is not None:
            return reason
    return None


def _differs(estimator: BaseEstimator) -> str | None:
    """Where skl2onnx converts the estimator but the graph predicts otherwise (found by
    checking every catalogue entry), what it is; else None."""
    name = type(estimator).__name__
    params = estimator.get_params(deep=False)
    inner = params.get("estimator")
    if params.get("weights") == "distance":
        # an instance at distance 0 (a training instance) weighs infinitely: scikit-learn
        # takes its label, the graph's 1/0 gives NaN
        return f"{name} weighted by distance"
    if name == "SGDClassifier" and params.get("loss") in ("log_loss", "modified_huber"):
        # scikit-learn's label is the decision function's, the graph's the probabilities'
        return f"{name} with probabilities"
    if name == "VotingClassifier" and params.get("voting") == "hard":
        return "hard VotingClassifier"
    if name == "OneVsRestClassifier" and not hasattr(inner, "predict_proba"):
        return "OneVsRestClassifier of a classifier without probabilities"
    if name == "CalibratedClassifierCV" and type(inner).__name__ == "GaussianNB":
        return "CalibratedClassifierCV of GaussianNB"
    return None


#: scikit-learn estimators skl2onnx has no converter for (or none that matches ours).
_NO_CONVERTER = frozenset(
    {
        "OutputCodeClassifier",
        "GaussianProcessClassifier",
        "GaussianProcessRegressor",
        "TransformedTargetRegressor",
        "RegressorChain",
        "KBinsDiscretizer",
        "CategoricalNB",
        "DummyRegressor",
        "NearestCentroid",
    }
)

#: The catalogue's wrappers of LightGBM and CatBoost (:mod:`benchmark.catalogue.boosters`).
WRAPPED_BOOSTERS = frozenset({"LightGBMClassifier", "CatBoostNominalClassifier"})


def refuse(classifier: str, what: str) -> NoReturn:
    """Refuse ``classifier`` (``what`` of it has no converter), naming what exports."""
    raise ConfigurationError(
        f"classifier '{classifier}' ({what}) has no ONNX converter; exportable: {SUPPORTED}"
    )
