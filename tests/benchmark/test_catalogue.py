"""The classifier catalogue: content, lookup, and every entry fitting tiny awkward data."""

from __future__ import annotations

import re
from collections.abc import Iterator

import numpy as np
import pytest
from sklearn.base import clone
from sklearn.ensemble import RandomForestClassifier
from sklearn.linear_model import LogisticRegression
from sklearn.naive_bayes import GaussianNB
from sklearn.neighbors import KNeighborsClassifier
from sklearn.svm import SVC
from sklearn.tree import DecisionTreeClassifier
from threadpoolctl import threadpool_limits

from benchmark.catalogue import CATALOGUE, ClassifierSpec, build_pipeline, get_spec, suite
from benchmark.catalogue.estimators import LabelEncodedClassifier, OneRuleClassifier
from benchmark.errors import ConfigurationError

FAMILIES = {
    "majority",
    "rules",
    "trees",
    "forests",
    "bagging",
    "boosting",
    "nearest-neighbours",
    "naive-bayes",
    "discriminant-analysis",
    "logistic",
    "svm",
    "neural-network",
    "linear-sgd",
    "linear",
    "prototype",
    "gaussian-process",
    "calibration",
    "multiclass-wrapper",
    "voting",
    "stacking",
}


@pytest.fixture(autouse=True)
def single_thread() -> Iterator[None]:
    """Fit with one BLAS/OpenMP thread, as the engine's workers do, on a shared machine."""
    with threadpool_limits(limits=1):
        yield


def tiny_data(seed: int = 0) -> tuple[np.ndarray, np.ndarray, dict[int, int]]:
    """180 instances: 4 numeric features, 2 nominal ones (3 and 4 labels), NaNs in both.

    Labels are 0, 2 and 3 of four declared classes (class 1 never occurs), as in a fold
    or a chain that lacks a class.
    """
    rng = np.random.default_rng(seed)
    y = np.repeat([0, 2, 3], 60)
    numeric = rng.normal(size=(180, 4)) + y[:, None] * np.array([1.0, -0.5, 0.3, 0.0])
    colour = (y + rng.integers(0, 2, size=180)) % 3
    shape = rng.integers(0, 4, size=180)
    X = np.column_stack([numeric[:, :2], colour, numeric[:, 2:], shape]).astype(np.float64)
    X[rng.random(X.shape) < 0.08] = np.nan
    return X, y, {2: 3, 5: 4}


def test_catalogue_has_at_least_fifty_configurations_with_stable_ids() -> None:
    assert len(CATALOGUE) >= 50
    for classifier_id, spec in CATALOGUE.items():
        assert spec.id == classifier_id
        assert re.fullmatch(r"[a-z0-9]+(-[a-z0-9]+)*", classifier_id), classifier_id
        assert spec.family in FAMILIES, (classifier_id, spec.family)
        assert spec.cost in ("fast", "slow")
        assert spec.suites <= {"fast", "default"}


def test_every_family_of_the_issue_is_covered() -> None:
    assert {spec.family for spec in CATALOGUE.values()} == FAMILIES


@pytest.mark.parametrize(
    ("classifier_id", "estimator_type", "weka_name"),
    [
        ("j48", DecisionTreeClassifier, "weka.classifiers.trees.J48"),
        ("rf", RandomForestClassifier, "weka.classifiers.trees.RandomForest"),
        ("nb", GaussianNB, "weka.classifiers.bayes.NaiveBayes"),
        ("ibk", KNeighborsClassifier, "weka.classifiers.lazy.IBk"),
        ("logistic", LogisticRegression, "weka.classifiers.functions.Logistic"),
        ("svm-rbf", SVC, "weka.classifiers.functions.SMO"),
    ],
)
def test_required_ids_mean_what_the_issue_says(
    classifier_id: str, estimator_type: type, weka_name: str
) -> None:
    spec = get_spec(classifier_id)
    estimator = spec.make_estimator()
    assert isinstance(estimator, estimator_type)
    assert spec.weka_name == weka_name


def test_required_ids_details() -> None:
    assert get_spec("j48").make_estimator().criterion == "entropy"
    assert get_spec("ibk").make_estimator().n_neighbors == 1
    assert get_spec("svm-rbf").make_estimator().kernel == "rbf"
    assert get_spec("zeror").make_estimator().strategy == "prior"
    assert type(get_spec("mlp").make_estimator()).__name__ == "MLPClassifier"
    xgb = get_spec("xgb").make_estimator()
    assert isinstance(xgb, LabelEncodedClassifier)
    assert type(xgb.estimator).__name__ == "XGBClassifier"


def test_unknown_id_suggests_the_closest() -> None:
    with pytest.raises(ConfigurationError, match=r"unknown classifier 'rff'; did you mean 'rf'\?"):
        get_spec("rff")
    with pytest.raises(ConfigurationError, match="unknown classifier 'qqqqqq'; see"):
        get_spec("qqqqqq")


def test_suites_nest_and_mark_slow_entries_honestly() -> None:
    fast, default, everything = suite("fast"), suite("default"), suite("all")
    assert {"zeror", "j48", "rf", "nb", "ibk", "logistic"} <= set(fast)
    assert set(fast) < set(default) < set(everything)
    assert everything == list(CATALOGUE)
    assert all(get_spec(i).cost == "fast" for i in fast)
    for slow in ("gp", "stacking", "gbm"):
        assert get_spec(slow).cost == "slow"
    assert "gp" not in default
    with pytest.raises(ConfigurationError, match="unknown suite 'quick'"):
        suite("quick")


def test_spec_to_json_is_plain_data() -> None:
    data = get_spec("rf").to_json()
    assert data["id"] == "rf"
    assert data["estimator"] == "sklearn.ensemble._forest.RandomForestClassifier"
    assert data["params"] == {"n_estimators": 100}
    assert "all" in data["suites"]


@pytest.mark.filterwarnings("ignore:Bins whose width are too small:UserWarning")
@pytest.mark.parametrize("classifier_id", list(CATALOGUE))
def test_every_entry_fits_and_predicts_nominal_and_missing_inputs(classifier_id: str) -> None:
    X, y, nominal = tiny_data()
    spec = get_spec(classifier_id)
    model = build_pipeline(classifier_id, nominal_features=nominal, n_features=X.shape[1])
    model.fit(X[::2], y[::2])
    predicted = model.predict(X[1::2])
    assert predicted.shape == (90,)
    assert set(predicted) <= {0, 2, 3}
    assert list(model.classes_) == [0, 2, 3]
    assert hasattr(model, "predict_proba") == spec.probabilities
    if spec.probabilities:
        proba = model.predict_proba(X[1::2])
        assert proba.shape == (90, 3)
        np.testing.assert_allclose(proba.sum(axis=1), 1.0, rtol=1e-6)
    if classifier_id != "zeror":
        training = model.predict(X[::2])
        assert np.mean(training == y[::2]) > 0.4, "no better than chance on its training data"


def test_extra_columns_after_the_features_pass_through() -> None:
    X, y, nominal = tiny_data()
    extra = (y[:, None] == np.array([0, 2])).astype(np.float64)
    model = build_pipeline("logistic", nominal_features=nominal, n_features=X.shape[1])
    model.fit(np.hstack([X, extra]), y)
    assert model.score(np.hstack([X, extra]), y) == 1.0
    transformed = model.named_steps["preprocess"].transform(np.hstack([X, extra]))
    np.testing.assert_array_equal(transformed[:, -2:], extra)


def test_random_state_reaches_nested_estimators() -> None:
    model = build_pipeline("stacking", n_features=3, random_state=7)
    seeds = {k: v for k, v in model.get_params(deep=True).items() if k.endswith("random_state")}
    assert seeds and set(seeds.values()) == {7}


def test_histogram_boosting_gets_nominal_columns_natively() -> None:
    X, y, nominal = tiny_data()
    model = build_pipeline("hgb", nominal_features=nominal, n_features=X.shape[1])
    model.fit(X, y)
    # numeric columns 0, 1, 3, 4 come first, then the nominal codes 2 and 5
    assert model.named_steps["classifier"].categorical_features == [4, 5]
    assert model.named_steps["classifier"].is_categorical_.tolist() == [0, 0, 0, 0, 1, 1]


def test_nominal_columns_with_too_many_labels_fall_back_to_one_hot() -> None:
    model = build_pipeline("hgb", nominal_features={0: 300}, n_features=2)
    assert model.named_steps["classifier"].categorical_features == "from_dtype"


def test_build_pipeline_accepts_a_spec_outside_the_catalogue() -> None:
    spec = ClassifierSpec(
        id="my-tree",
        weka_name=None,
        family="trees",
        description="a test tree",
        factory=DecisionTreeClassifier,
        params={"max_depth": 2},
        probabilities=True,
        needs_scaling=False,
        handles_missing=True,
        handles_nominal=False,
        cost="fast",
        suites=frozenset(),
    )
    model = build_pipeline(spec, n_features=6)
    assert model.named_steps["classifier"].max_depth == 2


def test_label_encoded_classifier_handles_any_labels_and_a_single_class() -> None:
    X, y, _ = tiny_data()
    X = np.nan_to_num(X)
    wrapped = LabelEncodedClassifier(LogisticRegression())
    wrapped.fit(X, y + 10)
    assert set(wrapped.predict(X)) <= {10, 12, 13}
    assert wrapped.predict_proba(X).shape == (180, 3)
    single = clone(wrapped).fit(X, np.full(180, 5))
    assert single.predict(X[:3]).tolist() == [5, 5, 5]
    assert single.predict_proba(X[:3]).tolist() == [[1.0], [1.0], [1.0]]


def test_one_rule_picks_the_informative_feature() -> None:
    rng = np.random.default_rng(1)
    y = np.repeat([0, 1, 2], 30)
    X = rng.normal(size=(90, 5))
    X[:, 3] = y * 10 + rng.normal(size=90)
    rule = OneRuleClassifier().fit(X, y)
    assert rule.feature_ == 3
    assert rule.score(X, y) == 1.0
