"""Exporting a model as ONNX, and choosing what runs its predictions (the engine).

An export is checked before it is stored: the graph must give the model's labels, and its
probabilities within :data:`benchmark.export.onnx.TOLERANCE`, on every instance of the data
set the model was trained on.  The twin is kept in the store beside the model
(``model_exports``) with its sha256, which is verified on every load; ONNX bytes are a
graph of operators, not code, so loading them runs nothing of the writer's.
"""

from __future__ import annotations

from touchbench.app.errors import ConflictError, FieldError
from touchbench.app.schemas.models import ExportRequest, ExportSchema
from touchbench.app.services.loading import load_model
from touchbench.app.services.models import align_features
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import load_dataset
from touchbench.app.store.exports import load_export, save_export
from touchbench.app.store.models import ModelInfo, get_model
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.extras import MissingExtraError
from touchbench.benchmark.problem import restrict_targets


def export_model(store: Store, request: ExportRequest) -> tuple[ExportSchema, bytes]:
    """Convert a stored model, check the graph on its training instances, store it as the
    model's twin, and return it.

    Raises
    ------
    FieldError
        The model has no converter (naming what is supported), or the graph disagrees with
        the model (naming the largest difference): for ``model``.
    ConflictError
        The data set the model was trained on is gone: nothing to check the graph on.
    NotFoundError
        No such model.
    """
    from touchbench.benchmark.export.onnx import export_onnx  # start-up time: skl2onnx, onnxruntime

    info, model = load_model(store, request.model)
    if info.dataset_id is None:
        raise ConflictError(
            f"model '{info.name}': the data set it was trained on was deleted, so its ONNX "
            "graph cannot be checked against it; train the model again to export it"
        )
    data = load_dataset(store, info.dataset_id)
    data = restrict_targets(data, [t.name for t in model.schema.targets])
    X = align_features(model.schema, data, source=info.name)
    try:
        graph = export_onnx(model, X)
    except MissingExtraError:
        raise
    except ConfigurationError as error:
        raise FieldError("model", str(error)) from None
    saved = save_export(store, info.id, request.format, graph)
    return (
        ExportSchema(
            model=info.name,
            model_id=info.id,
            format=saved.format,
            sha256=saved.sha256,
            size_bytes=saved.size_bytes,
            checked_instances=int(X.shape[0]),
        ),
        graph,
    )


def stored_export(store: Store, ref: str | int) -> tuple[ModelInfo, bytes, bool]:
    """A model's stored ONNX twin, exported (and stored) first if it has none; and whether
    it was exported now."""
    info = get_model(store, ref)
    graph = load_export(store, info.id, "onnx")
    if graph is not None:
        return info, graph, False
    _, graph = export_model(store, ExportRequest(model=info.id))
    return info, graph, True
