"""Predict one instance with a model exported by ``touchbench export-model``.

Needs only ONNX Runtime and numpy (``pip install onnxruntime numpy``), not touchbench:
this is what a robot's own program does, in Python; a C or C++ program does the same
steps with ONNX Runtime's C API (``OrtGetApiBase``, ``CreateSession``,
``SessionGetModelMetadata`` / ``ModelMetadataLookupCustomMetadataMap`` for the keys below,
one ``CreateTensorWithDataAsOrtValue`` over a ``float[n_features]`` buffer, ``Run``).

    python examples/predict_onnx.py model.onnx instance.json

``instance.json`` holds one instance as ``{"attribute": value}``: numbers for numeric
attributes, labels (text) for nominal ones, ``null`` for a missing value.  It prints
``{"label": ..., "probabilities": {...}}`` (or ``{"value": [...]}`` for a regressor); for
a model of several targets, each target's answer under its name:
``{"label": {"gesture": "tap", "place": "arm"}, "probabilities": {"gesture": {...}, ...}}``.

The graph's metadata says how to fill its input:

- ``touchbench.features``: JSON list of the input's columns in order, each
  ``{"name", "kind"}`` and, for a nominal attribute, its ``labels`` (the column holds the
  index of the label, NaN when missing);
- ``touchbench.targets``: JSON list of the targets, each ``{"name", "labels", "label",
  "probabilities"}``: the output named by ``label`` is an index into ``labels``, and the
  columns of the output named by ``probabilities`` follow them (``label`` and
  ``probabilities`` for one target, ``label_<name>`` and ``probabilities_<name>`` for
  several).
"""

from __future__ import annotations

import json
import math
import sys

import numpy as np
import onnxruntime


def feature_row(columns: list[dict], instance: dict) -> np.ndarray:
    """The input row, float32 of shape (1, n_features), from ``{attribute: value}``."""
    row = np.full((1, len(columns)), np.nan, dtype=np.float32)
    for j, column in enumerate(columns):
        value = instance.get(column["name"])
        if value is None:
            continue  # missing: NaN, as in training
        if column["kind"] == "nominal":
            labels = column["labels"]
            row[0, j] = labels.index(value) if value in labels else math.nan
        else:
            row[0, j] = float(value)
    return row


def main(model_path: str, instance_path: str) -> None:
    session = onnxruntime.InferenceSession(model_path, providers=["CPUExecutionProvider"])
    metadata = session.get_modelmeta().custom_metadata_map
    columns = json.loads(metadata["touchbench.features"])
    if "touchbench.targets" in metadata:
        targets = json.loads(metadata["touchbench.targets"])
    else:  # a graph exported before the key was written: one target
        labels = json.loads(metadata["touchbench.labels"])
        targets = [{"name": "", "labels": labels, "label": "label"}]
        targets[0]["probabilities"] = "probabilities"
    with open(instance_path, encoding="utf-8") as handle:
        instance = json.load(handle)
    outputs = [output.name for output in session.get_outputs()]
    results = dict(
        zip(
            outputs, session.run(outputs, {"features": feature_row(columns, instance)}), strict=True
        )
    )
    if "value" in results:
        print(json.dumps({"value": results["value"][0].tolist()}))
        return
    labels, probabilities = {}, {}
    for target in targets:
        names = target["labels"]
        labels[target["name"]] = names[int(results[target["label"]][0])]
        if target["probabilities"] in results:
            row = results[target["probabilities"]][0]
            probabilities[target["name"]] = {
                label: float(p) for label, p in zip(names, row, strict=True)
            }
    if len(targets) == 1:
        [name] = labels
        answer: dict = {"label": labels[name]}
        if probabilities:
            answer["probabilities"] = probabilities[name]
    else:
        answer = (
            {"label": labels, "probabilities": probabilities}
            if probabilities
            else {"label": labels}
        )
    print(json.dumps(answer))


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: predict_onnx.py MODEL.onnx INSTANCE.json")
    main(sys.argv[1], sys.argv[2])
