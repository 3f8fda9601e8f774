"""Sequence data sets: the CHANNEL[T] layout, ARFF round trips, time-series classifiers."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest
import skops.io
from sklearn.ensemble import RandomForestClassifier
from sklearn.model_selection import cross_val_score
from threadpoolctl import threadpool_limits

from tests.support.sequences import CHANNELS, LENGTH, sequence_dataset, shapes
from touchbench.benchmark.artifacts import is_trusted_type
from touchbench.benchmark.catalogue import build_pipeline
from touchbench.benchmark.catalogue.neural import KINDS as NETWORKS
from touchbench.benchmark.dataset import Attribute, Dataset, Schema
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.estimators import check_classifier, reads_sequences
from touchbench.benchmark.io.arff import dumps_arff, loads_arff
from touchbench.benchmark.model import dumps_model, fit_model, loads_model, model_digest
from touchbench.benchmark.problem import problem_from_dataset
from touchbench.benchmark.sequence import find_sequence, panel, sequence_names


@pytest.fixture(autouse=True)
def single_thread() -> Iterator[None]:
    with threadpool_limits(limits=1):
        yield


def summary_statistics(sequences: np.ndarray) -> np.ndarray:
    """Per channel: mean, std, min, max and the deciles, shape (n, n_channels * 13)."""
    parts = [
        sequences.mean(axis=-1),
        sequences.std(axis=-1),
        sequences.min(axis=-1),
        sequences.max(axis=-1),
        *np.percentile(sequences, np.arange(10, 100, 10), axis=-1),
    ]
    return np.concatenate(parts, axis=1)


def test_names_record_the_shape_and_damage_makes_the_data_flat_with_a_note() -> None:
    names = ["gain", *sequence_names(CHANNELS, 3), "extra"]
    layout, note = find_sequence(names)
    assert note is None and layout is not None
    assert layout.shape == (1, 2, 3) and layout.stop == 7
    assert find_sequence(["a", "b"]) == (None, None)
    missing = [n for n in names if n != "z[1]"]
    assert find_sequence(missing)[0] is None
    assert "attribute 'z[2]' stands where 'z[1]' should" in str(find_sequence(missing)[1])
    shorter = [*names[:-2], "extra"]  # z has 2 steps, x has 3
    assert "channel 'z' has 2 steps, 'x' has 3" in str(find_sequence(shorter)[1])
    interrupted = ["x[0]", "gain", "x[1]"]
    assert "attribute 'gain' interrupts the block" in str(find_sequence(interrupted)[1])
    X = np.arange(2 * 8.0).reshape(2, 8)
    sequences, others = panel(X, layout.shape)
    assert sequences.shape == (2, 2, 3) and sequences[1, 1].tolist() == [12.0, 13.0, 14.0]
    assert others.tolist() == [[0.0, 7.0], [8.0, 15.0]]


def test_a_sequence_data_set_round_trips_through_arff_with_its_shape() -> None:
    sequences, y = shapes(n=6)
    data = sequence_dataset(sequences, y)
    text = dumps_arff(data)
    assert "@attribute x[0] numeric" in text and "@attribute z[47] numeric" in text
    again = loads_arff(text)
    assert again.equals(data)
    problem, notes = problem_from_dataset(again)
    assert problem.sequence is not None and notes == []
    assert (problem.sequence.channels, problem.sequence.length) == (CHANNELS, LENGTH)
    assert problem.sequence.start == 1  # after 'gain', among the features
    np.testing.assert_array_equal(panel(problem.X, problem.sequence.shape)[0], sequences)


@pytest.mark.slow
def test_flat_summaries_cannot_tell_the_shapes_apart_and_minirocket_can() -> None:
    sequences, y = shapes()
    flat = cross_val_score(
        RandomForestClassifier(n_estimators=200, random_state=0),
        summary_statistics(sequences),
        y,
        cv=4,
    ).mean()
    assert flat < 0.7, f"summary statistics separate the classes ({flat:.2f}): a weak test"
    problem, _ = problem_from_dataset(sequence_dataset(sequences, y))
    train, test = np.arange(80) % 4 != 0, np.arange(80) % 4 == 0
    for classifier in ("minirocket", "multirocket", "interval-forest"):
        model = build_pipeline(
            classifier, n_features=problem.n_features, sequence=problem.sequence, random_state=0
        )
        model.fit(problem.X[train], problem.Y[train, 0])
        accuracy = np.mean(model.predict(problem.X[test]) == problem.Y[test, 0])
        assert accuracy >= 0.9, (classifier, accuracy)


def test_sequence_classifiers_refuse_flat_data_sets_in_one_line() -> None:
    sequences, y = shapes(n=8)
    flat = Dataset(
        Schema(
            "flat",
            (
                Attribute("slope", "nominal", ("up", "down")),
                Attribute("parity", "nominal", ("even", "odd")),
                *(Attribute(f"s{i}", "numeric") for i in range(5)),
            ),
            (0,),
        ),
        np.column_stack([y, np.arange(8) // 2 % 2, summary_statistics(sequences)[:, :5]]),
    )
    problem, _ = problem_from_dataset(flat)
    for classifier in ("minirocket", "multirocket", "interval-forest", *NETWORKS):
        with pytest.raises(ConfigurationError) as error:
            check_classifier(classifier, problem)
        message = str(error.value)
        assert "\n" not in message
        assert message.startswith(f"classifier '{classifier}' needs a sequence data set")
    with pytest.raises(ConfigurationError, match="needs a sequence data set"):
        fit_model(flat, "minirocket")
    two_targets, _ = problem_from_dataset(flat.with_targets((0, 1)))
    with pytest.raises(ConfigurationError, match="'minirocket' needs a sequence data set"):
        check_classifier("bcc:minirocket", two_targets)
    check_classifier("bcc:rf", two_targets)
    assert reads_sequences("minirocket") and reads_sequences("bcc:minirocket")
    assert not reads_sequences("rf") and not reads_sequences("bcc:rf")


def test_sequences_too_short_for_minirocket_are_refused() -> None:
    names = sequence_names(("x",), 5)
    data = Dataset(
        Schema(
            "short",
            (Attribute("c", "nominal", ("a", "b")), *(Attribute(n, "numeric") for n in names)),
            (0,),
        ),
        np.column_stack([np.arange(6) % 2, np.ones((6, 5))]),
    )
    problem, _ = problem_from_dataset(data)
    with pytest.raises(ConfigurationError, match="needs sequences of at least 9 steps"):
        check_classifier("minirocket", problem)
    check_classifier("interval-forest", problem)


def test_flat_classifiers_and_multi_target_bases_work_on_sequence_data_sets() -> None:
    sequences, y = shapes(n=40)
    data = sequence_dataset(sequences, y)
    rf = fit_model(data, "rf")
    assert rf.predict(data.X).shape == (40, 1)
    second = Attribute("parity", "nominal", ("even", "odd"))
    schema = Schema(
        "shapes: -C 2", (data.schema.attributes[0], second, *data.schema.attributes[1:]), (0, 1)
    )
    both = Dataset(schema, np.column_stack([y, (np.arange(40) // 2) % 2, data.values[:, 1:]]))
    chain = fit_model(both, "cc:minirocket")
    predicted = chain.predict(both.X)
    assert predicted.shape == (40, 2)
    assert np.mean(predicted[:, 0] == y) == 1.0  # its training data


@pytest.mark.parametrize("variant", ["minirocket", "multirocket"])
def test_rockets_fit_and_transform_through_kernels_of_one_memory_layout(variant: str) -> None:
    """A rocket's numba kernels compile once per argument type and memory layout (cached
    ahead by scripts/compile_kernels.py for C-contiguous float32 and an integer seed, as
    runs give): a sequence block read out of a data set's columns (column-major) is a
    strided view, and must not compile another."""
    from aeon.transformations.collection.convolution_based import _minirocket, _multirocket

    from touchbench.benchmark.catalogue.time_series import RocketClassifier

    sequences, y = shapes(n=20)
    columns = sequence_dataset(sequences, y).X  # the gain, then the sequences
    assert not columns.flags.c_contiguous
    model = RocketClassifier(
        variant, n_kernels=84, sequence=(1, len(CHANNELS), LENGTH), random_state=0
    )
    model.fit(columns, y).predict(columns)
    kernels = {
        "minirocket": [_minirocket._fit_biases, _minirocket._static_transform_multi],
        "multirocket": [_multirocket._fit_biases_multivariate, _multirocket._transform_multi],
    }[variant]
    layouts = {
        kernel.__name__: {signature[0].layout for signature in kernel.signatures}
        for kernel in kernels
    }
    assert layouts == {kernel.__name__: {"C"} for kernel in kernels}


def test_a_trained_minirocket_round_trips_naming_only_its_own_aeon_class() -> None:
    sequences, y = shapes(n=40)
    data = sequence_dataset(sequences, y)
    model = fit_model(data, "minirocket")
    blob = dumps_model(model)
    named = skops.io.get_untrusted_types(data=blob)
    aeon = [name for name in named if name.startswith("aeon.")]
    assert aeon == ["aeon.transformations.collection.convolution_based._minirocket.MiniRocket"]
    assert all(is_trusted_type(name) for name in named)
    loaded = loads_model(blob, sha256=model_digest(blob))
    np.testing.assert_array_equal(loaded.predict(data.X), model.predict(data.X))
    # the rest of aeon stays untrusted: a crafted artifact cannot name its other classes
    assert not is_trusted_type("aeon.classification.interval_based._drcif.DrCIFClassifier")
    assert not is_trusted_type("aeon.transformations.collection.feature_based._catch22.Catch22")
