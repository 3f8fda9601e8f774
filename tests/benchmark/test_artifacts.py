"""Model artifacts cannot run code: crafted artifacts are refused before anything is built."""

from __future__ import annotations

import io
import json
import pickle
import zipfile
from pathlib import Path

import numpy as np
import pytest

from tests.support.synthetic import nominal_dataset as dataset
from touchbench.benchmark.artifacts import dumps_artifact, is_trusted_type, loads_artifact
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.model import dumps_model, fit_model, loads_model, model_digest


class _Touch:
    """A pickle payload: unpickling it creates a file (it would run any code just as well)."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def __reduce__(self) -> tuple[object, tuple[object, ...]]:
        return (Path.touch, (self.path,))


def _with_node(artifact: bytes, module: str, name: str) -> bytes:
    """``artifact`` with its estimator node claiming to be an object of ``module.name``."""
    archive = zipfile.ZipFile(io.BytesIO(artifact))
    schema = json.loads(archive.read("schema.json"))
    estimator = schema["content"]["estimator"]
    estimator["__class__"], estimator["__module__"] = name, module
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w") as crafted:
        crafted.writestr("schema.json", json.dumps(schema))
        for name_in_zip in archive.namelist():
            if name_in_zip != "schema.json":
                crafted.writestr(name_in_zip, archive.read(name_in_zip))
    return out.getvalue()


def test_a_model_round_trips_through_its_artifact() -> None:
    data = dataset()
    model = fit_model(data, "rf")
    blob = dumps_model(model)
    again = loads_model(blob, sha256=model_digest(blob))
    assert again.schema == model.schema and again.classifier == "rf"
    np.testing.assert_array_equal(again.predict(data.X), model.predict(data.X))
    np.testing.assert_allclose(again.predict_proba(data.X)[0], model.predict_proba(data.X)[0])


def test_a_pickle_with_a_matching_digest_is_refused_and_runs_nothing(tmp_path: Path) -> None:
    marker = tmp_path / "pwned"
    crafted = pickle.dumps(_Touch(marker))
    with pytest.raises(ConfigurationError, match="not a skops artifact"):
        loads_model(crafted, sha256=model_digest(crafted))
    assert not marker.exists()


@pytest.mark.parametrize(
    ("module", "name"),
    [("subprocess", "Popen"), ("os", "system"), ("builtins", "eval"), ("pathlib", "Path")],
)
def test_an_artifact_naming_untrusted_types_is_refused_before_loading(
    tmp_path: Path, module: str, name: str
) -> None:
    marker = tmp_path / "pwned"
    genuine = dumps_model(fit_model(dataset(), "nb"))
    crafted = _with_node(genuine, module, name)
    with pytest.raises(ConfigurationError, match="does not trust"):
        loads_model(crafted, sha256=model_digest(crafted))
    assert not marker.exists()


def test_only_classes_of_trusted_packages_are_trusted() -> None:
    assert is_trusted_type("sklearn.ensemble._forest.RandomForestClassifier")
    assert is_trusted_type("xgboost.sklearn.XGBClassifier")
    assert is_trusted_type("touchbench.benchmark.multitarget.chains.ClassifierChain")
    assert not is_trusted_type("numpy.save")  # a function of a trusted package
    assert not is_trusted_type("numpy.load")
    assert not is_trusted_type("numpy.memmap")
    assert not is_trusted_type("os.system")
    assert not is_trusted_type("builtins.eval")
    assert not is_trusted_type("sklearn.nothing_here.Missing")
    assert not is_trusted_type("benchmarkevil.Thing")


def test_foreign_skops_content_is_not_a_model() -> None:
    import skops.io

    foreign = skops.io.dumps({"hello": "world"})
    with pytest.raises(ConfigurationError, match="not a touchbench model"):
        loads_artifact(foreign)
    assert loads_artifact(dumps_artifact({"x": [1, 2]}))["x"] == [1, 2]
