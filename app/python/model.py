"""A trained model in Python: predictions on a DataFrame, and its ONNX graph written out."""

from __future__ import annotations

# Imports inside functions: start-up time: pandas loads with the first DataFrame predicted.
from pathlib import Path
from typing import TYPE_CHECKING, Any

from touchbench.app.python.data import FRAME, features_of
from touchbench.app.schemas.models import ExportRequest
from touchbench.app.services.export import export_model
from touchbench.app.services.loading import load_predictor
from touchbench.app.services.models import Predictions, predict
from touchbench.app.store.database import Store
from touchbench.app.store.models import ModelInfo
from touchbench.benchmark.dataset import Schema

if TYPE_CHECKING:
    import pandas as pd


class Model:
    """A stored model (``touchbench.train`` returns one), as ``touchbench predict`` uses it.

    Parameters
    ----------
    info : ModelInfo
        The stored model's description.
    store : Store
        The store it is kept in.
    """

    def __init__(self, info: ModelInfo, store: Store) -> None:
        self.info = info
        self._store = store

    @property
    def name(self) -> str:
        """``NAME@VERSION``, as the CLI and the service name it."""
        return self.info.label

    @property
    def classifier(self) -> str:
        return self.info.classifier

    @property
    def targets(self) -> list[str]:
        return list(self.info.targets)

    def __repr__(self) -> str:
        return f"<Model {self.name}: {self.classifier} predicting {', '.join(self.targets)}>"

    def _predictions(self, data: pd.DataFrame) -> Predictions:
        _, predictor = load_predictor(self._store, self.info.id, "native")
        schema = Schema.from_json(self.info.schema)
        return predict(predictor, features_of(data, schema), source=FRAME)

    def predict(self, data: pd.DataFrame) -> Any:
        """The predicted label (or number) of each row.

        Parameters
        ----------
        data : DataFrame of shape (n_rows, ...)
            The model's feature columns by name (others, such as a label, are ignored).

        Returns
        -------
        pandas.Series of shape (n_rows,) for one target, else a DataFrame of shape
        (n_rows, n_targets).
        """
        import pandas as pd

        labels = self._predictions(data).labels
        frame = pd.DataFrame({t: list(v) for t, v in labels.items()}, index=data.index)
        return frame.iloc[:, 0] if frame.shape[1] == 1 else frame

    def predict_proba(self, data: pd.DataFrame) -> pd.DataFrame:
        """Each row's probability of every label.

        Returns
        -------
        pandas.DataFrame of shape (n_rows, n_labels)
            One column per label (``target=label`` with several targets).

        Raises
        ------
        AppError
            The classifier gives no probabilities, or the model predicts numbers.
        """
        import pandas as pd

        from touchbench.app.errors import AppError

        found = self._predictions(data)
        if found.probabilities is None:
            raise AppError(f"model '{self.name}' ({self.classifier}) gives no probabilities")
        several = len(found.probabilities) > 1
        columns = {}
        for target, matrix in found.probabilities.items():
            for j, label in enumerate(found.class_labels[target]):
                columns[f"{target}={label}" if several else label] = matrix[:, j]
        return pd.DataFrame(columns, index=data.index)

    def export_onnx(self, path: str | Path) -> Path:
        """Convert the model to ONNX (checked against the model on its training instances,
        kept as its twin in the store, as ``touchbench export-model`` does) and write the
        graph to ``path``.

        Raises
        ------
        MissingExtraError
            The ``onnx`` extra is not installed.
        FieldError
            The classifier has no ONNX converter.
        """
        _, graph = export_model(self._store, ExportRequest(model=self.info.id))
        target = Path(path)
        target.write_bytes(graph)
        return target
