"""BCC over random forests on a small sample of the UC3M touch data (gesture + place)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from sklearn.model_selection import StratifiedKFold

from touchbench.benchmark.io.arff import read_arff
from touchbench.benchmark.multitarget import build_multitarget, multitarget_scores

SAMPLE = 600


@pytest.mark.shared
@pytest.mark.parametrize("robot", ["mini", "maggie"])
def test_bcc_over_random_forest_on_a_sample(shared_datasets: Path, robot: str) -> None:
    dataset = read_arff(shared_datasets / "uc3m-touch" / robot / "gesture_and_place.arff")
    assert dataset.schema.target_names == ("gesture", "place")
    n_classes = tuple(len(target.values) for target in dataset.schema.targets)
    rows = np.random.default_rng(0).choice(dataset.n_instances, SAMPLE, replace=False)
    X, Y = dataset.X[rows], dataset.Y[rows].astype(np.int64)
    joint = np.ravel_multi_index(tuple(Y.T), n_classes)
    hamming, exact = [], []
    for train, test in StratifiedKFold(3, shuffle=True, random_state=0).split(X, joint):
        model = build_multitarget("bcc:rf", n_features=dataset.n_features, n_classes=n_classes)
        model.fit(X[train], Y[train])
        assert sorted(model.tree_.tolist()) == [-1, model.root_]
        scores = multitarget_scores(
            Y[test],
            model.predict(X[test]),
            model.predict_proba(X[test]),
            n_classes=n_classes,
            target_names=dataset.schema.target_names,
        )
        assert set(scores["per_target"]) == {"gesture", "place"}
        # Place is the easy target (the paper: 1.000 with the full data).
        assert (
            scores["per_target"]["place"]["accuracy"] > scores["per_target"]["gesture"]["accuracy"]
        )
        hamming.append(scores["hamming_score"])
        exact.append(scores["exact_match"])
    # With a fifth of the data, 3 folds: about 0.89 (Mini) and 0.88 (Maggie); the full
    # data under 10 folds reaches the paper's 0.90 (perf/multitarget_real.py).
    assert np.mean(hamming) > 0.85
    assert np.mean(exact) > 0.7
    assert np.mean(exact) < np.mean(hamming)
