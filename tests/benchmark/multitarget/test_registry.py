"""The ``META:BASE`` registry: listing, parsing, building, checking targets."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.base import clone

from tests.support.multitarget import three_targets
from touchbench.benchmark.catalogue import CATALOGUE
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.multitarget import (
    DEFAULT_BASES,
    META_METHODS,
    MultiTargetClassifier,
    build_multitarget,
    check_targets,
    multitarget_configurations,
    parse_config,
)

MEKA_METHODS = ("cr", "cc", "bcc", "pcc", "lc", "ps", "eps", "ecc", "rakeld", "nsr", "scc")


def test_at_least_ten_methods_over_eight_bases() -> None:
    configurations = multitarget_configurations()
    assert len(configurations) == len(set(configurations)) == 11 * 8
    metas = {c.split(":")[0] for c in configurations}
    bases = {c.split(":")[1] for c in configurations}
    assert metas == set(MEKA_METHODS)
    assert bases == set(DEFAULT_BASES)
    assert "bcc:rf" in configurations and "cc:svm-rbf" in configurations
    assert "lc:xgb" in configurations


def test_default_bases_exist_in_the_catalogue() -> None:
    assert set(DEFAULT_BASES) <= set(CATALOGUE)


def test_multi_label_methods_are_flagged_and_listed_on_request() -> None:
    binary_only = {meta for meta, spec in META_METHODS.items() if spec.binary_only}
    assert binary_only == {
        "ml-br", "ml-cc", "ml-lp", "ml-rakeld", "ml-rakelo", "mlknn", "brknn", "mlaram"
    }  # fmt: skip
    assert not any(META_METHODS[m].binary_only for m in MEKA_METHODS)
    listed = multitarget_configurations(bases=["j48"], include_multilabel=True)
    assert "ml-br:j48" in listed and "mlknn" in listed and "mlknn:j48" not in listed
    assert not any(c.startswith("ml") for c in multitarget_configurations())


def test_every_listed_configuration_parses() -> None:
    for config in multitarget_configurations(include_multilabel=True):
        meta, base = parse_config(config)
        assert config == (f"{meta}:{base}" if base else meta)


@pytest.mark.parametrize(
    ("config", "message"),
    [
        ("bbc:rf", "unknown multi-target method 'bbc' in 'bbc:rf'; did you mean 'bcc'"),
        ("bcc:rff", "unknown classifier 'rff'; did you mean 'rf'"),
        ("bcc", "'bcc' lacks a base classifier: write bcc:BASE, e.g. bcc:rf"),
        ("bcc:", "lacks a base classifier"),
        ("mlknn:rf", "'mlknn' takes no base classifier"),
        ("zzz:rf", r"known: cr, cc, bcc"),
    ],
)
def test_bad_configuration_ids(config: str, message: str) -> None:
    with pytest.raises(ConfigurationError, match=message):
        parse_config(config)


def test_build_gives_a_fresh_unfitted_estimator_seeded_and_sized() -> None:
    model = build_multitarget("bcc:cart", n_features=4, random_state=7, n_classes=[3, 2, 3])
    assert isinstance(model, MultiTargetClassifier)
    assert not hasattr(model, "n_classes_")
    assert model.get_params()["random_state"] == 7
    assert model.get_params()["n_classes"] == (3, 2, 3)
    assert model.get_params()["estimator__classifier__random_state"] == 7
    assert build_multitarget("bcc:j48", n_features=4) is not build_multitarget(
        "bcc:j48", n_features=4
    )


@pytest.mark.parametrize("meta", MEKA_METHODS)
def test_every_method_fits_through_the_registry(meta: str) -> None:
    X, Y = three_targets(n_samples=60)
    model = build_multitarget(f"{meta}:j48", n_features=4, n_classes=(3, 2, 3))
    model = clone(model).fit(X, Y)
    assert model.predict(X).shape == (60, 3)


@pytest.mark.parametrize("base", DEFAULT_BASES)
def test_every_default_base_fits_under_a_chain(base: str) -> None:
    X, Y = three_targets(n_samples=60)
    model = build_multitarget(f"cc:{base}", n_features=4, n_classes=(3, 2, 3))
    if base == "xgb":
        # 300 boosting rounds per link are the catalogue's; 20 keep this test quick.
        model.set_params(estimator__classifier__estimator__n_estimators=20)
    model.fit(X, Y)
    proba = model.predict_proba(X)
    assert [p.shape for p in proba] == [(60, 3), (60, 2), (60, 3)]
    assert model.score(X, Y) > 0.5


def test_check_targets_refuses_one_target() -> None:
    with pytest.raises(ConfigurationError, match="has 1 target \\(gesture\\)"):
        check_targets("bcc:rf", [4], ["gesture"])


def test_check_targets_refuses_multi_label_methods_on_multi_class_targets() -> None:
    with pytest.raises(ConfigurationError, match=r"binary targets only, but gesture \(4"):
        check_targets("ml-br:rf", [4, 2], ["gesture", "touched"])
    check_targets("ml-br:rf", [2, 2], ["a", "b"])
    check_targets("bcc:rf", [4, 3], ["gesture", "place"])


def test_multi_label_method_without_base_gets_the_catalogue_preprocessing() -> None:
    rng = np.random.default_rng(0)
    X = rng.normal(size=(80, 3))
    Y = (X[:, :2] > 0).astype(int)
    X[rng.random(X.shape) < 0.1] = np.nan
    model = build_multitarget("mlknn", n_features=3).fit(X, Y)
    assert model.score(X, Y) > 0.7
