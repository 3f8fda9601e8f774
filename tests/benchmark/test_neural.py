"""The neural entries (``bilstm``, ``cnn1d``, ``resnet1d``, ``inception-time``): the
estimator contract, one seed for equal fits, early stopping on whole recordings, the
engine's limits, safe artifacts, and regression on x, y.

The catalogue's parametrised test fits every entry on tiny windows; here, a few epochs.
"""

from __future__ import annotations

import os
import pickle
import struct
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import skops.io
from sklearn.base import clone
from sklearn.pipeline import Pipeline

from tests.support.sequences import sequence_dataset, shapes
from touchbench.benchmark.artifacts import dumps_artifact, loads_artifact
from touchbench.benchmark.catalogue import build_pipeline, get_spec
from touchbench.benchmark.catalogue.neural import (
    NeuralSequenceClassifier,
    NeuralSequenceRegressor,
    _validation_split,
    check_architecture,
)
from touchbench.benchmark.catalogue.regressors import REGRESSORS, regression_suite, regressor_spec
from touchbench.benchmark.dataset import Attribute, Dataset, Schema
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.estimators import check_classifier, group_fit_params
from touchbench.benchmark.model import dumps_model, fit_model, loads_model, model_digest
from touchbench.benchmark.problem import Problem, problem_from_dataset
from touchbench.benchmark.run.engine import run_tasks
from touchbench.benchmark.run.folds import Fold, make_folds
from touchbench.benchmark.sequence import SequenceLayout, sequence_names

QUICK = {"max_epochs": 6, "learning_rate": 0.01}


def quick(classifier_id: str, layout: SequenceLayout, **params: object) -> Pipeline:
    model = build_pipeline(classifier_id, n_features=layout.stop, sequence=layout)
    return model.set_params(**{f"classifier__{k}": v for k, v in {**QUICK, **params}.items()})


def windows(n: int = 40) -> tuple[np.ndarray, np.ndarray, SequenceLayout]:
    sequences, y = shapes(n)
    layout = SequenceLayout(start=0, channels=("a", "b"), length=sequences.shape[2])
    return sequences.reshape(n, -1), y, layout


def test_parameters_round_trip_through_clone_and_set_params() -> None:
    model = NeuralSequenceClassifier(network="cnn1d", filters=8, sequence=(0, 2, 64))
    params = model.get_params()
    assert params["network"] == "cnn1d" and params["sequence"] == (0, 2, 64)
    twin = clone(model)
    assert twin.get_params() == params and twin is not model
    assert clone(NeuralSequenceRegressor(hidden=7)).set_params(layers=2).get_params()["layers"] == 2
    assert get_spec("bilstm").make_estimator().get_params()["network"] == "bilstm"


@pytest.mark.parametrize(
    ("classifier_id", "size"),
    [("cnn1d", {}), ("bilstm", {}), ("inception-time", {"filters": 4, "layers": 3})],
)
def test_two_fits_with_one_seed_give_equal_predictions(
    classifier_id: str, size: dict[str, int]
) -> None:
    X, y, layout = windows()
    first = quick(classifier_id, layout, **size).fit(X[::2], y[::2])
    second = quick(classifier_id, layout, **size).fit(X[::2], y[::2])
    np.testing.assert_array_equal(first.predict_proba(X[1::2]), second.predict_proba(X[1::2]))
    assert first[-1].weights_ == second[-1].weights_
    other = quick(classifier_id, layout, random_state=1, **size).fit(X[::2], y[::2])
    assert other[-1].weights_ != first[-1].weights_


def test_early_stopping_keeps_the_best_epoch_of_the_inner_validation_split() -> None:
    X, y, layout = windows()
    model = quick("cnn1d", layout, max_epochs=40, patience=2).fit(X, y)[-1]
    (best,), (run,) = model.best_epoch_, model.n_epochs_
    assert best <= run <= best + 2
    assert run < 40


def test_refit_trains_a_new_network_on_the_whole_fold_for_the_best_epoch_count() -> None:
    X, y, layout = windows()
    refitted = quick("cnn1d", layout, max_epochs=12, patience=3).fit(X, y)[-1]
    kept = quick("cnn1d", layout, max_epochs=12, patience=3, refit=False).fit(X, y)[-1]
    assert refitted.n_epochs_ == kept.n_epochs_ and refitted.best_epoch_ == kept.best_epoch_
    assert refitted.n_refit_epochs_ == kept.best_epoch_ and kept.n_refit_epochs_ == 0
    assert refitted.weights_ != kept.weights_  # not the best epoch's weights of the search
    # The same seed, every instance, the best epoch count and no validation split.
    (best,) = kept.best_epoch_
    whole = quick("cnn1d", layout, max_epochs=best, refit=False, validation_fraction=0.0)
    assert whole.fit(X, y)[-1].weights_ == refitted.weights_


def test_a_network_stored_before_refit_existed_loads_as_it_was_trained() -> None:
    X, y, layout = windows()
    model = quick("cnn1d", layout, max_epochs=1).fit(X, y)[-1]
    state = model.__getstate__()
    del state["refit"]
    old = NeuralSequenceClassifier.__new__(NeuralSequenceClassifier)
    old.__setstate__(state)
    assert old.get_params()["refit"] is False  # it kept the best epoch's weights
    np.testing.assert_array_equal(old.predict_proba(X), model.predict_proba(X))


def test_several_networks_average_the_probabilities_of_their_seeds() -> None:
    X, y, layout = windows()
    ensemble = quick("cnn1d", layout, n_networks=2, random_state=3).fit(X[::2], y[::2])
    alone = [quick("cnn1d", layout, random_state=s).fit(X[::2], y[::2]) for s in (3, 4)]
    mean = np.mean([model.predict_proba(X[1::2]) for model in alone], axis=0)
    np.testing.assert_allclose(ensemble.predict_proba(X[1::2]), mean, rtol=1e-6)
    np.testing.assert_array_equal(ensemble.predict(X[1::2]), ensemble.classes_[mean.argmax(1)])
    assert ensemble[-1].n_epochs_.tolist() == [m[-1].n_epochs_[0] for m in alone]
    assert ensemble[-1].architecture_["n_networks"] == 2
    # A network stored before ensembles existed: one network, its weights' own names.
    state = alone[0][-1].__getstate__()
    del state["n_networks"]
    state["architecture_"] = {k: v for k, v in state["architecture_"].items() if k != "n_networks"}
    old = NeuralSequenceClassifier.__new__(NeuralSequenceClassifier)
    old.__setstate__(state)
    assert old.n_networks == 1 and old.architecture_["n_networks"] == 1
    np.testing.assert_array_equal(old.predict_proba(X), alone[0].predict_proba(X))


def test_early_stopping_holds_out_whole_groups_when_given_them() -> None:
    y = np.arange(60) % 3
    groups = np.repeat(np.arange(20), 3)  # a recording's three windows, one of each class
    train, valid = _validation_split(y, 0.15, 0, groups)
    assert valid.size and not set(groups[train]) & set(groups[valid])
    assert sorted(np.concatenate([train, valid])) == list(range(60))
    few = np.arange(60) % 4
    train, valid = _validation_split(y, 0.15, 0, few)  # too few groups: instances
    assert valid.size == 9 and set(few[train]) & set(few[valid])
    train, valid = _validation_split(y, 0.15, 0)  # instances, stratified
    assert np.bincount(y[valid]).tolist() == [3, 3, 3]


def test_the_engine_and_training_give_the_groups_to_a_network_only() -> None:
    X, y, layout = windows()
    groups = np.arange(len(y)) // 4
    network = quick("cnn1d", layout, refit=False)  # the weights of the split's best epoch
    assert group_fit_params(network, groups)["classifier__groups"] is not None
    assert group_fit_params(network, None) == {}
    assert group_fit_params(build_pipeline("rf", n_features=layout.stop), groups) == {}
    with pytest.raises(ValueError, match="one entry per instance"):
        network.fit(X, y, classifier__groups=groups[:-1])
    grouped = network.fit(X, y, **group_fit_params(network, groups))[-1]
    ungrouped = quick("cnn1d", layout, refit=False).fit(X, y)[-1]
    assert grouped.weights_ != ungrouped.weights_  # another validation split was held out


@pytest.fixture(scope="module")
def problem_and_fold() -> tuple[Problem, list[Fold]]:
    problem, _ = problem_from_dataset(sequence_dataset(*shapes(40)))
    folds, _ = make_folds(problem.Y, n_folds=2, seed=0)
    return problem, folds[:1]


def test_the_task_timeout_stops_training_and_the_run_goes_on(problem_and_fold) -> None:
    problem, fold = problem_and_fold
    endless = replace(
        get_spec("bilstm"),
        id="bilstm-endless",
        params={"network": "bilstm", "max_epochs": 10**6, "patience": 10**6},
    )
    results = run_tasks(  # nb first: one worker serves both
        problem, ["nb", "bilstm-endless"], fold, timeout=3.0, extra_specs={endless.id: endless}
    )
    status = {r.key.classifier: (r.status, r.error) for r in results}
    assert status["bilstm-endless"] == ("timeout", "timed out after 3 s (worker process killed)")
    assert status["nb"] == ("ok", None)


def test_the_memory_limit_fails_the_task_and_the_run_goes_on(problem_and_fold) -> None:
    problem, fold = problem_and_fold
    results = run_tasks(problem, ["nb", "cnn1d"], fold, timeout=120, max_memory=100 * 2**20)
    status = {r.key.classifier: r for r in results}
    assert status["cnn1d"].status == "error"
    assert str(status["cnn1d"].error).startswith("exceeded the memory limit of 100 MB")
    assert status["nb"].status == "ok"


def test_a_trained_network_round_trips_through_its_artifact() -> None:
    data = sequence_dataset(*shapes(40))
    model = fit_model(data, "cnn1d")
    stored = dumps_model(model)
    assert b"torch" not in stored  # arrays, bytes and plain data only: no PyTorch object
    loaded = loads_model(stored, sha256=model_digest(stored))
    X = data.X
    np.testing.assert_array_equal(loaded.predict(X), model.predict(X))
    np.testing.assert_allclose(loaded.predict_proba(X)[0], model.predict_proba(X)[0])


class _Payload:
    """Unpickling it creates ``path``: proof that a pickle was run."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def __reduce__(self) -> tuple[object, tuple[str]]:
        return (os.mkdir, (str(self.path),))


def _crafted(**state: object) -> bytes:
    """A fitted cnn1d's artifact with some of its state replaced."""
    X, y, layout = windows()
    model = quick("cnn1d", layout, max_epochs=1).fit(X, y)
    model[-1].__dict__.update(state)
    return dumps_artifact({"estimator": model})


def test_a_crafted_network_artifact_is_refused_before_anything_runs(tmp_path: Path) -> None:
    pwned = tmp_path / "pwned"
    torch_pickle = pickle.dumps({"out.weight": _Payload(pwned)})
    header = b'{"w": {"dtype": "O", "shape": [1], "data_offsets": [0, 8]}}'
    objects = struct.pack("<Q", len(header)) + header + bytes(8)
    for state, message in (
        ({"weights_": torch_pickle}, "weights are not safetensors"),
        ({"weights_": objects}, "weight 'w' is not float32 or int64"),
        ({"architecture_": {"kind": "os.system"}}, "unknown or missing keys"),
    ):
        with pytest.raises(ConfigurationError, match=message):
            loads_artifact(_crafted(**state))
    assert not pwned.exists()
    base = _crafted()
    architecture = skops.io.loads(base, trusted=skops.io.get_untrusted_types(data=base))
    kind = dict(architecture["estimator"][-1].architecture_, kind="subprocess")
    with pytest.raises(ConfigurationError, match="unknown network kind 'subprocess'"):
        loads_artifact(_crafted(architecture_=kind))
    huge = dict(kind, kind="bilstm", hidden=10**9)
    with pytest.raises(ValueError, match="'hidden' must lie in"):
        check_architecture(huge)


def test_weights_that_do_not_fit_the_architecture_are_refused_on_prediction() -> None:
    X, y, layout = windows()
    cnn = quick("cnn1d", layout, max_epochs=1).fit(X, y)
    lstm = quick("bilstm", layout, max_epochs=1).fit(X, y)
    lstm[-1].__dict__.update(weights_=cnn[-1].weights_, _networks=None)
    with pytest.raises(ValueError, match="weights do not fit its architecture"):
        lstm.predict(X)


def xy_windows(n: int = 60, seed: int = 0) -> Dataset:
    """Touches at (x, y): a wave whose frequency follows x and whose level follows y."""
    rng = np.random.default_rng(seed)
    x, y = rng.uniform(0, 10, n), rng.uniform(-5, 5, n)
    steps = np.arange(32)
    wave = np.sin(2 * np.pi * (1 + x[:, None] / 4) * steps / 32 + rng.uniform(0, 6, (n, 1)))
    block = np.stack([wave, wave + y[:, None] / 2], axis=1) + 0.05 * rng.normal(size=(n, 2, 32))
    names = sequence_names(("a", "b"), 32)
    attributes = (
        *(Attribute(name, "numeric") for name in names),
        Attribute("x", "numeric"),
        Attribute("y", "numeric"),
    )
    values = np.column_stack([block.reshape(n, -1), x, y])
    return Dataset(Schema("touch: -C -2", attributes, (64, 65)), values, name="touch")


def test_a_network_regresses_the_position_of_touches() -> None:
    data, test = xy_windows(), xy_windows(30, seed=1)
    problem, _ = problem_from_dataset(data)
    assert problem.kind == "regression" and problem.sequence is not None
    model = fit_model(data, "cnn1d")
    predicted = model.predict_values(test.X)
    assert predicted.shape == (30, 2)
    error = np.abs(predicted - test.Y).mean(axis=0)
    baseline = np.abs(data.Y.mean(axis=0) - test.Y).mean(axis=0)
    assert (error < 0.6 * baseline).all(), (error, baseline)
    stored = dumps_model(model)
    loaded = loads_model(stored, sha256=model_digest(stored))
    np.testing.assert_array_equal(loaded.predict_values(test.X), predicted)
    with pytest.raises(ConfigurationError, match="predicts every target with one network"):
        regressor_spec("rc:bilstm", n_targets=2)


def test_sequence_regressors_are_offered_and_accepted_on_windows_only() -> None:
    flat = regression_suite("all", n_targets=2, n_instances=50)
    assert not {"bilstm", "cnn1d", "rc:bilstm"} & set(flat)
    assert {"bilstm", "cnn1d"} <= set(
        regression_suite("all", n_targets=2, n_instances=50, sequences=True)
    )
    problem, _ = problem_from_dataset(xy_windows())
    flat_problem = replace(problem, sequence=None)
    with pytest.raises(ConfigurationError, match="classifier 'bilstm' needs a sequence data set"):
        check_classifier("bilstm", flat_problem)
    assert check_classifier("bilstm", problem) is REGRESSORS["bilstm"]
