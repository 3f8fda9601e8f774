"""The WEKA-named catalogue entries predict what Debian's WEKA 3.6 predicts, row for row.

Each entry runs through the catalogue's own pipeline (nominal codes and label counts
handed over, no imputation) on a fixed train/test split of WEKA's example files, and its
predictions are compared with those of ``java weka.classifiers... -t train -T test -p 0``
run on the same split.  Skipped, saying so, where WEKA or Java is not installed
(``scripts/install.sh`` installs both).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from touchbench.benchmark.catalogue import build_pipeline, get_spec
from touchbench.benchmark.dataset import Dataset
from touchbench.benchmark.io.arff import read_arff, write_arff
from touchbench.benchmark.problem import problem_from_dataset
from touchbench.benchmark.weka.reference import (
    WEKA_DATA,
    cross_validated_accuracy,
    predictions,
    weka_jar,
)

pytestmark = pytest.mark.skipif(
    weka_jar() is None or not WEKA_DATA.is_dir(),
    reason="needs WEKA and Java (apt-get install weka default-jre-headless)",
)

ENTRIES = (
    "zeror",
    "j48",
    "j48-unpruned",
    "part",
    "nb",
    "nb-kernel",
    "nb-discretized",
    "ibk",
    "ibk5-w",
)


def split(name: str, folder: Path) -> tuple[Dataset, Dataset, Path, Path]:
    """Two thirds for training, one third for testing, drawn once with a fixed seed."""
    data = read_arff(WEKA_DATA / f"{name}.arff")
    order = np.random.default_rng(0).permutation(data.n_instances)
    cut = 2 * data.n_instances // 3
    train, test = data.subset(np.sort(order[:cut])), data.subset(np.sort(order[cut:]))
    paths = folder / f"{name}-train.arff", folder / f"{name}-test.arff"
    for dataset, path in zip((train, test), paths, strict=True):
        with path.open("w") as stream:
            write_arff(dataset, stream)
    return train, test, *paths


@pytest.fixture(scope="module", params=["breast-cancer", "labor"])
def weka_split(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> tuple:
    return split(request.param, tmp_path_factory.mktemp("weka"))


@pytest.mark.slow
@pytest.mark.parametrize("classifier_id", ENTRIES)
def test_predictions_equal_wekas(weka_split: tuple, classifier_id: str) -> None:
    train, test, train_path, test_path = weka_split
    spec = get_spec(classifier_id)
    assert spec.weka_command is not None
    fit, _ = problem_from_dataset(train)
    held_out, _ = problem_from_dataset(test)
    model = build_pipeline(
        spec, nominal_features=fit.nominal_features, n_features=fit.n_features
    ).fit(fit.X, fit.Y[:, 0])
    theirs = predictions(spec.weka_command, train_path, test_path)
    np.testing.assert_array_equal(model.predict(held_out.X), theirs)


@pytest.mark.slow
def test_wekas_cross_validation_is_read() -> None:
    accuracy = cross_validated_accuracy("weka.classifiers.rules.ZeroR", WEKA_DATA / "iris.arff")
    assert accuracy == pytest.approx(100 / 3, abs=0.01)
