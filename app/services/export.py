"""A model's twin in ONNX: made (converted, checked, stored) as a job or by the command line,
never inside a request that reads; read back as stored.

An export is checked before it is stored: the graph must give the model's labels, and its
probabilities within :data:`benchmark.export.onnx.TOLERANCE`, on every instance of the data
set the model was trained on.  The twin is kept in the store beside the model
(``model_exports``) with its sha256, which is verified on every load; ONNX bytes are a
graph of operators, not code, so loading them runs nothing of the writer's.  Converting a
large model takes seconds and a great deal of memory: the service does it in a job
(:func:`app.services.jobs.submit_export`), one per model at a time.
"""

from __future__ import annotations

# Imports inside functions: start-up time: the converters (skl2onnx, onnx) and the catalogue
# load only where a model is exported or checked for it.
from touchbench.app.errors import ConflictError, FieldError, NotFoundError
from touchbench.app.schemas.models import ExportRequest, ExportSchema
from touchbench.app.services.alignment import align_features
from touchbench.app.services.loading import load_model
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import load_dataset
from touchbench.app.store.exports import export_under_way, load_export, save_export
from touchbench.app.store.models import ModelInfo, get_model
from touchbench.benchmark.dataset import Schema
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.extras import MissingExtraError
from touchbench.benchmark.problem import restrict_targets


class TwinMissing(NotFoundError):  # noqa: N818 (a state of the model, answered 404)
    """The model has no twin in the format, and none is being made."""


class TwinUnderWay(ConflictError):  # noqa: N818 (a state of the model, answered 409)
    """The model's twin is being made by a job (``job``)."""

    def __init__(self, message: str, job: int) -> None:
        super().__init__(message)
        self.job = job


def export_model(store: Store, request: ExportRequest) -> tuple[ExportSchema, bytes]:
    """Convert a stored model, check the graph on its training instances, store it as the
    model's twin (replacing one it had), and return it.

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
    from touchbench.benchmark.export.onnx import export_onnx  # start-up time: see above

    info, model = load_model(store, request.model)
    _refuse_without_data(info)
    assert info.dataset_id is not None  # refused above
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


def check_export(store: Store, request: ExportRequest) -> ModelInfo:
    """The model ``request`` names, once what its export would refuse without converting
    anything was refused: before a job is queued, or before a model is trained with a twin.

    Raises
    ------
    NotFoundError
        No such model.
    ConflictError
        The data set it was trained on is gone.
    FieldError
        Models of its classifier have no converter (for ``model``).
    MissingExtraError
        The ``onnx`` extra is not installed.
    """
    info = get_model(store, request.model)
    _refuse_without_data(info)
    refuse_unexportable(info.classifier, regression=_is_regression(info), field="model")
    return info


def refuse_unexportable(classifier: str, *, regression: bool, field: str) -> None:
    """Refuse a classifier whose models the catalogue says do not export, before one is
    trained or converted; what the catalogue does not know of is left to the export.

    Raises
    ------
    FieldError
        For ``field``, in the words of the export's own refusal.
    MissingExtraError
        The ``onnx`` extra is not installed.
    """
    # start-up time: see above
    from touchbench.benchmark.catalogue import get_spec
    from touchbench.benchmark.export.multitarget import exports_multitarget
    from touchbench.benchmark.export.onnx import exports_onnx
    from touchbench.benchmark.export.supported import SUPPORTED
    from touchbench.benchmark.extras import EXTRAS, require
    from touchbench.benchmark.multitarget import parse_config

    require(EXTRAS["onnx"].modules, "exporting a model to ONNX")
    if regression:
        return  # the catalogue's entries are classifiers; the export judges regressors
    try:
        if ":" in classifier:
            meta, base = parse_config(classifier)
            exports = exports_multitarget(meta, bool(base) and exports_onnx(get_spec(base)))
        else:
            exports = exports_onnx(get_spec(classifier))
    except ConfigurationError:
        return  # not in the catalogue (a plug-in, a WEKA command line)
    if not exports:
        raise FieldError(
            field,
            f"classifier '{classifier}' has no ONNX converter; exportable: {SUPPORTED}",
        )


def stored_twin(store: Store, ref: str | int, format: str = "onnx") -> tuple[ModelInfo, bytes]:
    """A model's stored twin, as it is: never made here.

    Raises
    ------
    TwinUnderWay
        A job is making it (``job``).
    TwinMissing
        It has none, and none is being made.
    AppError
        Its bytes differ from their recorded digest.
    """
    info = get_model(store, ref)
    graph = load_export(store, info.id, format)
    if graph is not None:
        return info, graph
    job = export_under_way(store, info.id, format)
    if job is not None:
        raise TwinUnderWay(f"model '{info.label}': its ONNX twin is being made by job {job}", job)
    raise TwinMissing(f"model '{info.label}' has no ONNX twin yet")


def _refuse_without_data(info: ModelInfo) -> None:
    if info.dataset_id is None:
        raise ConflictError(
            f"model '{info.name}': the data set it was trained on was deleted, so its ONNX "
            "graph cannot be checked against it; train the model again to export it"
        )


def _is_regression(info: ModelInfo) -> bool:
    return all(target.kind == "numeric" for target in Schema.from_json(info.schema).targets)
