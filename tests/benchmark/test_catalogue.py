"""The classifier catalogue: content, lookup, and every entry fitting tiny awkward data."""

from __future__ import annotations

import re
from collections.abc import Iterator

import numpy as np
import pytest
from sklearn.base import clone
from sklearn.ensemble import HistGradientBoostingClassifier, RandomForestClassifier
from sklearn.linear_model import LogisticRegression
from sklearn.svm import SVC
from sklearn.tree import DecisionTreeClassifier
from threadpoolctl import threadpool_limits

from touchbench.benchmark.artifacts import dumps_artifact, loads_artifact
from touchbench.benchmark.catalogue import (
    CATALOGUE,
    ClassifierSpec,
    build_pipeline,
    get_spec,
    parse_weka_command,
    suite,
)
from touchbench.benchmark.catalogue.estimators import LabelEncodedClassifier, OneRuleClassifier
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.sequence import SequenceLayout
from touchbench.benchmark.weka import C45Classifier, WekaIBk, WekaNaiveBayes, WekaZeroR

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
    "time-series",
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


def with_sequence(X: np.ndarray, y: np.ndarray, seed: int = 0) -> tuple[np.ndarray, SequenceLayout]:
    """``X`` followed by a 2-channel sequence of 16 steps whose shape follows the class,
    NaNs in it too: the block starts after the nominal columns 2 and 5."""
    rng = np.random.default_rng(seed)
    steps = np.arange(16)
    waves = np.sin(
        2 * np.pi * (1 + y[:, None, None]) * steps / 16 + rng.uniform(0, 6, (len(y), 2, 1))
    )
    block = (waves + 0.2 * rng.normal(size=waves.shape)).reshape(len(y), -1)
    block[rng.random(block.shape) < 0.02] = np.nan
    layout = SequenceLayout(start=X.shape[1], channels=("a", "b"), length=16)
    return np.hstack([X, block]), layout


def test_catalogue_has_at_least_a_hundred_configurations_with_stable_ids() -> None:
    assert len(CATALOGUE) >= 100
    for classifier_id, spec in CATALOGUE.items():
        assert spec.id == classifier_id
        assert re.fullmatch(r"[a-z0-9]+(-[a-z0-9]+)*", classifier_id), classifier_id
        assert spec.family in FAMILIES, (classifier_id, spec.family)
        assert spec.cost in ("fast", "slow")
        assert spec.suites <= {"fast", "default"}


def test_every_family_of_the_issue_is_covered() -> None:
    assert {spec.family for spec in CATALOGUE.values()} == FAMILIES


@pytest.mark.parametrize(
    ("classifier_id", "estimator_type", "weka_command"),
    [
        ("zeror", WekaZeroR, "weka.classifiers.rules.ZeroR"),
        ("j48", C45Classifier, "weka.classifiers.trees.J48 -C 0.25 -M 2"),
        ("j48-unpruned", C45Classifier, "weka.classifiers.trees.J48 -U -M 2"),
        ("nb", WekaNaiveBayes, "weka.classifiers.bayes.NaiveBayes"),
        ("nb-kernel", WekaNaiveBayes, "weka.classifiers.bayes.NaiveBayes -K"),
        ("nb-discretized", WekaNaiveBayes, "weka.classifiers.bayes.NaiveBayes -D"),
        (
            "ibk",
            WekaIBk,
            "weka.classifiers.lazy.IBk -K 1 -W 0 -A "
            '"weka.core.neighboursearch.LinearNNSearch -A \\"weka.core.EuclideanDistance '
            '-R first-last\\""',
        ),
        ("rf", RandomForestClassifier, None),
        ("logistic", LogisticRegression, None),
        ("svm-rbf", SVC, None),
    ],
)
def test_required_ids_mean_what_the_issue_says(
    classifier_id: str, estimator_type: type, weka_command: str | None
) -> None:
    spec = get_spec(classifier_id)
    assert isinstance(spec.make_estimator(), estimator_type)
    assert spec.weka_command == weka_command
    assert spec.weka_name == (weka_command.split()[0] if weka_command else None)


def test_weka_names_only_on_estimators_that_compute_what_weka_computes() -> None:
    named = {i for i, spec in CATALOGUE.items() if spec.weka_command}
    assert {"zeror", "j48", "nb", "ibk"} <= named
    for classifier_id in named:
        estimator = get_spec(classifier_id).make_estimator()
        assert type(estimator).__module__.startswith("touchbench.benchmark.weka."), classifier_id
    commands = [CATALOGUE[i].weka_command for i in named]
    assert len(set(commands)) == len(commands), "two entries claim the same WEKA command"


def test_required_ids_details() -> None:
    j48 = get_spec("j48").make_estimator()
    assert (j48.confidence, j48.min_instances, j48.pruned, j48.subtree_raising) == (
        0.25,
        2,
        True,
        True,
    )
    assert get_spec("ibk").make_estimator().n_neighbors == 1
    assert get_spec("ibk-w").make_estimator().weighting == "inverse"
    assert get_spec("svm-rbf").make_estimator().kernel == "rbf"
    assert type(get_spec("mlp").make_estimator()).__name__ == "MLPClassifier"
    xgb = get_spec("xgb").make_estimator()
    assert isinstance(xgb, LabelEncodedClassifier)
    assert type(xgb.estimator).__name__ == "XGBClassifier"


@pytest.mark.parametrize("classifier_id", [i for i, s in CATALOGUE.items() if s.weka_command])
def test_every_weka_command_reads_back_to_its_entry(classifier_id: str) -> None:
    spec = get_spec(classifier_id)
    assert spec.weka_command is not None
    assert parse_weka_command(spec.weka_command) is spec
    short = spec.weka_command.replace("weka.classifiers.", "").split(".", 1)[1]
    assert parse_weka_command(short) is spec


def test_a_weka_command_outside_the_catalogue_becomes_a_new_configuration() -> None:
    spec = parse_weka_command("weka.classifiers.trees.J48 -C 0.1 -M 5")
    assert spec.id == "j48-c0.1-m5" and spec.id not in CATALOGUE
    assert spec.params == {"confidence": 0.1, "min_instances": 5}
    assert spec.weka_command == "weka.classifiers.trees.J48 -C 0.1 -M 5"
    assert spec.suites == frozenset()
    model = build_pipeline(spec, n_features=3)
    assert model.named_steps["classifier"].min_instances == 5
    assert parse_weka_command("IBk -K 7 -I").params == {"n_neighbors": 7, "weighting": "inverse"}
    assert parse_weka_command("weka.classifiers.trees.J48").id == "j48"


@pytest.mark.parametrize(
    ("command", "message"),
    [
        ("weka.classifiers.trees.J48 -B", r"J48: option '-B' is not supported by touchbench"),
        ("J48 -R -N 3", r"option '-R' is not supported"),
        ("J48 -C x", r"option '-C x': expected a number"),
        ("J48 -C 0.7", r"option '-C 0.7': the value must be at most 0.5"),
        ("J48 -M", r"option '-M' needs a value"),
        ("J48 -M 2 -M 3", r"option '-M' is given twice"),
        ("J48 -U -S", r"option '-S' .* makes no sense with '-U'"),
        ("NaiveBayes -K -D", r"options '-K' and '-D' exclude each other"),
        ("IBk -X", r"IBk: option '-X' is not supported"),
        (
            'IBk -A "weka.core.neighboursearch.KDTree"',
            r"option '-A weka.core.neighboursearch.KDTree'",
        ),
        (
            "weka.classifiers.functions.SMO",
            r"does not reproduce WEKA's 'weka.classifiers.functions.SMO'",
        ),
        ('J48 "-C', r"cannot read WEKA command line"),
        ("", r"empty WEKA command line"),
    ],
)
def test_unsupported_weka_commands_are_refused_naming_the_option(
    command: str, message: str
) -> None:
    with pytest.raises(ConfigurationError, match=message):
        parse_weka_command(command)


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
    for slow in ("gp", "stacking", "gbm", "catboost", "ripper"):
        assert get_spec(slow).cost == "slow"
    assert not {"gp", "gbm", "stacking"} & set(default)
    with pytest.raises(ConfigurationError, match="unknown suite 'quick'"):
        suite("quick")


def test_spec_to_json_is_plain_data() -> None:
    data = get_spec("rf").to_json()
    assert data["id"] == "rf"
    assert data["estimator"] == "sklearn.ensemble._forest.RandomForestClassifier"
    assert data["params"] == {"n_estimators": 100}
    assert "all" in data["suites"]
    assert data["weka_name"] is None and data["weka_command"] is None
    j48 = get_spec("j48").to_json()
    assert j48["weka_name"] == "weka.classifiers.trees.J48"
    assert j48["weka_command"] == "weka.classifiers.trees.J48 -C 0.25 -M 2"


@pytest.mark.filterwarnings("ignore:Bins whose width are too small:UserWarning")
@pytest.mark.parametrize(
    "classifier_id",
    # the sequence entries compile their kernels (numba) at their first fit
    [
        pytest.param(i, marks=pytest.mark.slow) if s.needs_sequence else i
        for i, s in CATALOGUE.items()
    ],
)
def test_every_entry_fits_and_predicts_nominal_and_missing_inputs(classifier_id: str) -> None:
    X, y, nominal = tiny_data()
    spec = get_spec(classifier_id)
    sequence = None
    if spec.needs_sequence:  # the flat columns beside the sequence reach them too
        X, sequence = with_sequence(X, y)
    model = build_pipeline(
        classifier_id, nominal_features=nominal, n_features=X.shape[1], sequence=sequence
    )
    if "classifier__max_epochs" in model.get_params():  # networks: a few quick epochs, narrow
        model.set_params(
            classifier__max_epochs=10, classifier__learning_rate=0.01, classifier__filters=8
        )
    if "classifier__n_kernels" in model.get_params():  # rockets: 84 kernels, not thousands
        model.set_params(classifier__n_kernels=84)
    # ensembles of trees (forests, boosting, bagging, also inside a vote): ten trees, not
    # hundreds; the fit, the predictions and the artifact round trip do the same per tree
    params = model.get_params(deep=True)
    model.set_params(
        **{
            name: 10
            for name, value in params.items()
            if isinstance(value, int)
            and value > 10
            and (
                name.endswith("n_estimators")
                or (
                    name.endswith("__max_iter")
                    and isinstance(params[name.rpartition("__")[0]], HistGradientBoostingClassifier)
                )
            )
        }
    )
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
    # the store's artifact format, with its allowlist of trusted types (no other trust)
    data = dumps_artifact({"estimator": model})
    loaded = loads_artifact(data)["estimator"]
    np.testing.assert_array_equal(loaded.predict(X[1::2]), predicted)


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
    # nothing to impute or scale: the columns keep their order, codes 2 and 5 nominal
    assert model.named_steps["classifier"].categorical_features == [2, 5]
    assert model.named_steps["classifier"].is_categorical_.tolist() == [0, 0, 1, 0, 0, 1]


@pytest.mark.parametrize("classifier_id", ["j48", "nb", "ibk", "lgbm", "catboost-shallow"])
def test_weka_and_boosting_estimators_get_nominal_codes_and_label_counts(
    classifier_id: str,
) -> None:
    X, y, nominal = tiny_data()
    extra = (y[:, None] == np.array([0, 2])).astype(np.float64)
    model = build_pipeline(classifier_id, nominal_features=nominal, n_features=X.shape[1])
    model.fit(np.hstack([X, extra]), y)
    assert model.named_steps["classifier"].nominal_features == {2: 3, 5: 4}
    passed = model.named_steps["preprocess"].transform(np.hstack([X, extra]))
    np.testing.assert_array_equal(passed, np.hstack([X, extra]))


def test_nominal_columns_with_too_many_labels_fall_back_to_one_hot() -> None:
    model = build_pipeline("hgb", nominal_features={0: 300}, n_features=2)
    assert model.named_steps["classifier"].categorical_features == "from_dtype"


def test_build_pipeline_accepts_a_spec_outside_the_catalogue() -> None:
    spec = ClassifierSpec(
        id="my-tree",
        weka_command=None,
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
