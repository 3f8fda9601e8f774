"""Neural networks on a sequence data set's windows: a BiLSTM, a 1-D CNN, a 1-D ResNet.

scikit-learn estimators of our own around PyTorch (:mod:`benchmark.catalogue.networks`),
as thin as the catalogue needs: ``__init__`` stores parameters, ``fit`` validates and sets
attributes ending in ``_``, so ``clone``, ``get_params``, pipelines and the engine's
workers treat them as any other entry.  Like the rockets (:mod:`.time_series`) they take
the flat feature matrix and a ``sequence`` parameter ``(start, n_channels, length)``:
the block is read as windows of shape (n_channels, length), the other columns go to the
output layer beside the network's features.

Training, all of it inside the training fold:

* standardisation per channel (sequences) and per column (other columns, and a
  regression's targets), fitted on the training fold;
* an inner validation split of the training fold (``validation_fraction``) for early
  stopping: training stops after ``patience`` epochs without a lower validation loss and
  keeps the weights of the best epoch.  Given the instances' ``groups`` (the engine gives
  a data set's recordings), whole groups are held out: windows of one recording share its
  contact force and resonances, and with sister windows on both sides the validation loss
  keeps falling while the network learns recordings rather than contacts (on the
  oscillating link it stopped later and scored lower on the test fold).  Without groups,
  the split is of instances, stratified for classes;
* then (``refit``, the default) a new network, same seed, learns the whole training fold
  for the best epoch's count of epochs: the held-out recordings are a sixth of the
  training data and, on the oscillating link, the contacts of a few recordings; leaving
  them out of the final network cost accuracy on the test fold;
* Adam, mini-batches, cross-entropy for classes and squared error for numbers;
* one seed (``random_state``) for the initial weights, the split and the batch order,
  with PyTorch's deterministic algorithms: two fits give equal predictions;
* ``n_networks`` above one trains that many networks, each with its own seed (the next
  integers), and averages their class probabilities (or values): an ensemble of seeds, as
  InceptionTime's authors make one.  A single network's accuracy on a test fold varies by
  a few points with its seed; the mean of several varies less and is higher on average;
* the threads of the process's ``OMP_NUM_THREADS`` (the engine's workers set it, 1
  unless asked), else one.

A fitted estimator holds no PyTorch object that is saved: its network is an
architecture (a dict of plain values, checked against :data:`ARCHITECTURE_BOUNDS` when
it is loaded) and its weights as safetensors bytes.  Model artifacts
(:mod:`benchmark.artifacts`) thus store arrays, bytes and plain data only; loading one
refuses an architecture outside the allowlist and weights that are not safetensors
before PyTorch sees anything.  The network itself is rebuilt on the first prediction and
kept (not saved) for the next ones.
"""

from __future__ import annotations

import contextlib
import json
import os
import resource
import struct
from collections.abc import Iterator, Mapping
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin, RegressorMixin
from sklearn.model_selection import GroupShuffleSplit, train_test_split
from sklearn.utils.validation import check_is_fitted, validate_data

from touchbench.benchmark.extras import require
from touchbench.benchmark.sequence import panel

#: The networks an architecture may name.
KINDS = ("bilstm", "cnn1d", "resnet1d", "inception-time")

#: Every key of an architecture and its allowed range (inclusive); nothing else is built.
ARCHITECTURE_BOUNDS: Mapping[str, tuple[float, float]] = {
    "n_channels": (1, 4096),
    "length": (1, 1_000_000),
    "n_others": (0, 100_000),
    "n_outputs": (1, 10_000),
    "hidden": (1, 2048),
    "layers": (1, 8),
    "filters": (1, 1024),
    "kernel": (1, 129),
    "dropout": (0.0, 0.9),
    "n_networks": (1, 16),
}
#: Weights a stored network may hold, and their element types in the safetensors header.
MAX_WEIGHT_BYTES = 1 << 30
WEIGHT_DTYPES = frozenset({"F32", "I64"})


def check_architecture(architecture: object) -> dict[str, Any]:
    """The architecture if it is one this module builds, else ``ValueError``.

    An architecture is a dict with exactly ``kind`` (one of :data:`KINDS`) and the keys
    of :data:`ARCHITECTURE_BOUNDS`, integers (``dropout`` a number) within their bounds.
    """
    if not isinstance(architecture, dict):
        raise ValueError(f"a network's architecture must be a dict, got {type(architecture)}")
    expected = {"kind", *ARCHITECTURE_BOUNDS}
    if set(architecture) != expected:
        odd = sorted(set(architecture) ^ expected)
        raise ValueError(f"a network's architecture has unknown or missing keys: {odd}")
    if architecture["kind"] not in KINDS:
        raise ValueError(f"unknown network kind {str(architecture['kind'])[:40]!r}")
    for key, (low, high) in ARCHITECTURE_BOUNDS.items():
        value = architecture[key]
        kind = float if key == "dropout" else int
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ValueError(f"architecture '{key}' must be a number, got {type(value).__name__}")
        if kind is int and not isinstance(value, int):
            raise ValueError(f"architecture '{key}' must be an integer, got {value!r}")
        if not low <= value <= high:
            raise ValueError(f"architecture '{key}' must lie in [{low}, {high}], got {value}")
    return architecture


def check_weights(weights: object) -> bytes:
    """Safetensors bytes (header read, nothing built) of float32 or int64 arrays, else
    ``ValueError``: a pickle, or any other format, is refused unread."""
    if not isinstance(weights, bytes) or len(weights) < 8 or len(weights) > MAX_WEIGHT_BYTES:
        raise ValueError("a network's weights must be safetensors bytes")
    (size,) = struct.unpack("<Q", weights[:8])
    if size > len(weights) - 8:
        raise ValueError("a network's weights are not safetensors (bad header length)")
    try:
        header = json.loads(weights[8 : 8 + size])
    except ValueError:
        raise ValueError("a network's weights are not safetensors (no JSON header)") from None
    if not isinstance(header, dict):
        raise ValueError("a network's weights are not safetensors (header is not a table)")
    for name, entry in header.items():
        if name == "__metadata__":
            continue
        if not isinstance(entry, dict) or entry.get("dtype") not in WEIGHT_DTYPES:
            raise ValueError(f"weight {name[:40]!r} is not float32 or int64")
    return weights


class _NeuralSequenceModel(BaseEstimator):
    """What the classifier and the regressor share: parameters, scaling, training loop."""

    #: The optional modules it needs (:mod:`benchmark.extras`).
    REQUIRES = ("torch", "safetensors")
    _loss = ""

    def __init__(
        self,
        network: str = "bilstm",
        hidden: int = 64,
        layers: int = 1,
        filters: int = 32,
        kernel: int = 5,
        dropout: float = 0.2,
        max_epochs: int = 60,
        patience: int = 8,
        batch_size: int = 32,
        learning_rate: float = 1e-3,
        validation_fraction: float = 0.15,
        refit: bool = True,
        n_networks: int = 1,
        sequence: tuple[int, int, int] | None = None,
        random_state: int | None = None,
    ) -> None:
        self.network = network
        self.hidden = hidden
        self.layers = layers
        self.filters = filters
        self.kernel = kernel
        self.dropout = dropout
        self.max_epochs = max_epochs
        self.patience = patience
        self.batch_size = batch_size
        self.learning_rate = learning_rate
        self.validation_fraction = validation_fraction
        self.refit = refit
        self.n_networks = n_networks
        self.sequence = sequence
        self.random_state = random_state

    # -- what subclasses say -----------------------------------------------------------

    def _targets(self, y: np.ndarray) -> np.ndarray:
        """Training targets as the network learns them: class indices or scaled values."""
        raise NotImplementedError

    def _n_outputs(self) -> int:
        raise NotImplementedError

    # -- state: a network is saved as plain data ----------------------------------------

    def __getstate__(self) -> dict[str, Any]:
        state = dict(super().__getstate__())
        state.pop("_networks", None)  # rebuilt from architecture_ and weights_
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        # An estimator stored before ``n_networks`` existed holds one network; before
        # ``refit`` existed, it kept the best epoch's weights.
        state.setdefault("n_networks", 1)
        state.setdefault("refit", False)
        architecture = state.get("architecture_")
        if isinstance(architecture, dict) and "n_networks" not in architecture:
            state["architecture_"] = {**architecture, "n_networks": 1}
        # Whoever wrote the state: refuse a network this module would not build, before
        # any of it reaches PyTorch (a model artifact is loaded through here).
        if "architecture_" in state:
            check_architecture(state["architecture_"])
            check_weights(state.get("weights_"))
        super().__setstate__(state)

    # -- fitting -------------------------------------------------------------------------

    def _fit(self, X: np.ndarray, y: np.ndarray, groups: np.ndarray | None) -> None:
        sequences, others = self._split(X)
        self.sequence_mean_, self.sequence_scale_ = _moments(sequences, axis=(0, 2))
        self.others_mean_, self.others_scale_ = _moments(others, axis=0)
        targets = self._targets(y)
        self.architecture_ = check_architecture(
            {
                "kind": self.network,
                "n_channels": int(sequences.shape[1]),
                "length": int(sequences.shape[2]),
                "n_others": int(others.shape[1]),
                "n_outputs": self._n_outputs(),
                "hidden": int(self.hidden),
                "layers": int(self.layers),
                "filters": int(self.filters),
                "kernel": int(self.kernel),
                "dropout": float(self.dropout),
                "n_networks": int(self.n_networks),
            }
        )
        inputs = self._scaled(sequences, others)
        with _torch_settings() as torch:
            self.weights_, epochs = _train(torch, self, inputs, targets, groups)
        self.n_epochs_, self.best_epoch_, self.n_refit_epochs_ = np.asarray(epochs).T
        self._networks: Any = None  # the built networks, kept for the next predictions

    def _outputs(self, X: np.ndarray) -> np.ndarray:
        """Each network's outputs, (n_networks, n_samples, n_outputs), for a feature
        matrix."""
        check_is_fitted(self, "weights_")
        X = validate_data(self, X, reset=False)
        sequences, others = self._scaled(*self._split(X))
        with _torch_settings() as torch:
            networks = getattr(self, "_networks", None)
            if networks is None:
                from touchbench.benchmark.catalogue.networks import load_networks  # PyTorch: on use

                networks = self._networks = load_networks(self.architecture_, self.weights_)
            inputs = torch.from_numpy(sequences), torch.from_numpy(others)
            with torch.inference_mode():
                outputs = [network(*inputs).numpy() for network in networks]
            return np.asarray(outputs, dtype=np.float64)

    def _split(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if self.sequence is None:
            raise ValueError(
                f"{type(self).__name__} needs its 'sequence' parameter (start, n_channels, "
                "length); build it with benchmark.catalogue.build_pipeline on a sequence data set"
            )
        start, n_channels, length = (int(value) for value in self.sequence)
        return panel(X, (start, n_channels, length))

    def _scaled(self, sequences: np.ndarray, others: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        mean, scale = self.sequence_mean_[None, :, None], self.sequence_scale_[None, :, None]
        scaled = ((sequences - mean) / scale).astype(np.float32)
        flat = ((others - self.others_mean_) / self.others_scale_).astype(np.float32)
        return np.ascontiguousarray(scaled), np.ascontiguousarray(flat)


class NeuralSequenceClassifier(ClassifierMixin, _NeuralSequenceModel):
    """A BiLSTM, 1-D CNN or 1-D ResNet classifier of a sequence data set's windows.

    Parameters
    ----------
    network : {"bilstm", "cnn1d", "resnet1d"}
        The network (:mod:`benchmark.catalogue.networks`).
    hidden : int
        LSTM units per direction (``bilstm``); units of the dense layer (``cnn1d``).
    layers : int
        Stacked LSTM layers (``bilstm``).
    filters : int
        Filters of the first convolution block; later blocks have twice as many.
    kernel : int
        Convolution width (``cnn1d``; ``resnet1d`` uses 7, 5 and 3).
    dropout : float
        Dropout before the output (and between LSTM layers).
    max_epochs, patience : int
        Epochs at most; epochs without a lower validation loss before stopping.
    batch_size : int
    learning_rate : float
        Adam's step size.
    validation_fraction : float
        Share of the training fold held out for early stopping (none below 10 instances:
        then all ``max_epochs`` are run).
    refit : bool
        After early stopping, train a new network (same seed) on the whole training fold
        for the best epoch's count of epochs; else keep the best epoch's weights.
    n_networks : int
        Networks trained, with seeds ``random_state``, ``random_state + 1``, ...; their
        class probabilities are averaged.
    sequence : (int, int, int) or None
        ``(start, n_channels, length)`` of the sequence block among the columns.
    random_state : int or None
        Seed of the weights, the validation split and the batch order (``None``: 0).

    Attributes
    ----------
    classes_ : ndarray of shape (n_classes,)
    architecture_ : dict
        The network's description (:func:`check_architecture`).
    weights_ : bytes
        The trained weights of every network, safetensors.
    n_epochs_, best_epoch_ : ndarray of shape (n_networks,)
        Epochs run by early stopping, and its best epoch (1-based), per network.
    n_refit_epochs_ : ndarray of shape (n_networks,)
        Epochs of the refit on the whole training fold, per network (0: none, the best
        epoch's weights were kept).
    """

    def fit(
        self, X: np.ndarray, y: np.ndarray, groups: np.ndarray | None = None
    ) -> NeuralSequenceClassifier:
        """Fit on ``X`` of shape (n_samples, n_columns) and labels ``y`` (n_samples,);
        ``groups`` (n_samples,), optional, keep a group on one side of the inner
        validation split."""
        X, y = validate_data(self, X, y)
        self._fit(X, y, _checked_groups(groups, len(y)))
        return self

    def _targets(self, y: np.ndarray) -> np.ndarray:
        self.classes_, codes = np.unique(y, return_inverse=True)
        return codes.astype(np.int64)

    def _n_outputs(self) -> int:
        return int(self.classes_.size)

    def predict_proba(self, X: np.ndarray) -> np.ndarray:
        """Probabilities of shape (n_samples, n_classes), columns as ``classes_``: the
        mean of the networks' softmax."""
        logits = self._outputs(X)
        logits -= logits.max(axis=2, keepdims=True)
        exp = np.exp(logits)
        return np.asarray((exp / exp.sum(axis=2, keepdims=True)).mean(axis=0))

    def predict(self, X: np.ndarray) -> np.ndarray:
        """Labels of shape (n_samples,)."""
        return np.asarray(self.classes_[np.argmax(self.predict_proba(X), axis=1)])


class NeuralSequenceRegressor(RegressorMixin, _NeuralSequenceModel):
    """A BiLSTM, 1-D CNN or 1-D ResNet regressor of one or several numeric targets.

    Parameters are :class:`NeuralSequenceClassifier`'s; targets are standardised on the
    training fold and the network's outputs mapped back.

    Attributes
    ----------
    target_mean_, target_scale_ : ndarray of shape (n_targets,)
    architecture_, weights_, n_epochs_, best_epoch_, n_refit_epochs_
        As the classifier's.
    """

    def fit(
        self, X: np.ndarray, y: np.ndarray, groups: np.ndarray | None = None
    ) -> NeuralSequenceRegressor:
        """Fit on ``X`` (n_samples, n_columns) and ``y`` (n_samples,) or (n_samples,
        n_targets); ``groups`` as the classifier's."""
        X, y = validate_data(self, X, y, multi_output=True, y_numeric=True)
        self._fit(X, y, _checked_groups(groups, len(y)))
        return self

    def _targets(self, y: np.ndarray) -> np.ndarray:
        self.target_shape_ = tuple(y.shape[1:])
        values = np.asarray(y, dtype=np.float64).reshape(len(y), -1)
        self.target_mean_, self.target_scale_ = _moments(values, axis=0)
        return ((values - self.target_mean_) / self.target_scale_).astype(np.float32)

    def _n_outputs(self) -> int:
        return int(self.target_mean_.size)

    def predict(self, X: np.ndarray) -> np.ndarray:
        """Values of shape (n_samples,) or (n_samples, n_targets), as ``y`` was: the
        mean of the networks'."""
        values = self._outputs(X).mean(axis=0) * self.target_scale_ + self.target_mean_
        return values.reshape(len(values), *self.target_shape_)


def _checked_groups(groups: np.ndarray | None, n: int) -> np.ndarray | None:
    """``groups`` as an array of ``n`` entries, or ``ValueError``."""
    if groups is None:
        return None
    groups = np.asarray(groups)
    if groups.shape != (n,):
        raise ValueError(f"groups must have one entry per instance ({n}), got {groups.shape}")
    return groups


def _moments(values: np.ndarray, axis: int | tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Mean and standard deviation along ``axis`` (1 where a column is constant)."""
    if values.size == 0:
        width = values.shape[1] if values.ndim > 1 else 0
        return np.zeros(width), np.ones(width)
    mean = values.mean(axis=axis)
    scale = values.std(axis=axis)
    return mean, np.where(scale > 1e-12, scale, 1.0)


def _threads() -> int:
    """``OMP_NUM_THREADS`` (the engine's workers set it), else one thread."""
    try:
        return max(1, int(os.environ.get("OMP_NUM_THREADS", "1")))
    except ValueError:
        return 1


def _memory_limited() -> bool:
    """Whether this process runs under a data-size limit (the engine's ``max_memory``)."""
    return resource.getrlimit(resource.RLIMIT_DATA)[0] != resource.RLIM_INFINITY


@contextlib.contextmanager
def _torch_settings() -> Iterator[Any]:
    """PyTorch with the process's thread count and deterministic algorithms; an
    allocation it cannot make becomes a ``MemoryError``, as NumPy's does."""
    require(_NeuralSequenceModel.REQUIRES, "the neural networks")
    try:
        import torch  # PyTorch costs seconds to import: only the processes that fit or predict
    except (ImportError, OSError, SystemError) as exc:
        # Under the engine's memory limit (RLIMIT_DATA) a failed allocation while PyTorch
        # loads shows as any of these; a SystemError "returned NULL without setting an
        # exception" is CPython's word for an allocation a C module did not report.
        if "memory" in str(exc).lower() or "map" in str(exc).lower() or _memory_limited():
            raise MemoryError(f"cannot load PyTorch: {exc}") from None
        raise
    torch.set_num_threads(_threads())
    deterministic = torch.are_deterministic_algorithms_enabled()
    torch.use_deterministic_algorithms(True)
    try:
        yield torch
    except RuntimeError as exc:
        if "can't allocate memory" in str(exc) or "not enough memory" in str(exc):
            raise MemoryError(str(exc).splitlines()[0]) from None
        raise
    finally:
        torch.use_deterministic_algorithms(deterministic)


def _train(
    torch: Any,
    model: _NeuralSequenceModel,
    inputs: tuple[np.ndarray, np.ndarray],
    y: np.ndarray,
    groups: np.ndarray | None,
) -> tuple[bytes, list[tuple[int, int, int]]]:
    """Train ``model``'s networks, one seed each; their weights, and per network the
    epochs run, the best epoch and the epochs refitted.

    Early stopping on the inner validation split finds the best epoch; with
    ``model.refit`` a new network (same seed) then learns the whole training fold for
    that many epochs, else the best epoch's weights are kept.
    """
    from touchbench.benchmark.catalogue.networks import network_bytes  # PyTorch: on use

    first = 0 if model.random_state is None else int(model.random_state)
    loss_of = torch.nn.CrossEntropyLoss() if y.dtype == np.int64 else torch.nn.MSELoss()
    data = (*(torch.from_numpy(part) for part in inputs), torch.from_numpy(y))
    everything = np.arange(len(y))
    networks, epochs = [], []
    for seed in range(first, first + int(model.n_networks)):
        train, valid = _validation_split(y, model.validation_fraction, seed, groups)
        network, epoch, best = _early_stopped(torch, model, data, loss_of, train, valid, seed)
        refitted = best if model.refit and valid.size and best else 0
        if refitted:
            network, _, _ = _early_stopped(
                torch, model, data, loss_of, everything, everything[:0], seed, refitted
            )
        networks.append(network)
        epochs.append((epoch, best, refitted))
    return network_bytes(networks), epochs


def _early_stopped(
    torch: Any,
    model: _NeuralSequenceModel,
    data: tuple[Any, Any, Any],
    loss_of: Any,
    train: np.ndarray,
    valid: np.ndarray,
    seed: int,
    epochs: int | None = None,
) -> tuple[Any, int, int]:
    """A new network trained on ``train`` for ``epochs`` (default ``model.max_epochs``),
    stopped after ``model.patience`` epochs without a lower loss on ``valid`` (if any);
    the network with the best epoch's weights, epochs run, best epoch."""
    from touchbench.benchmark.catalogue.networks import build_network  # PyTorch: on use

    torch.manual_seed(seed)
    rng = np.random.default_rng(seed)
    network = build_network(model.architecture_)
    optimiser = torch.optim.Adam(network.parameters(), lr=model.learning_rate)
    sequences, others, targets = data

    def snapshot() -> dict[str, Any]:
        return {name: value.detach().clone() for name, value in network.state_dict().items()}

    best, best_epoch, best_state, epoch = np.inf, 0, snapshot(), 0
    for epoch in range(1, int(model.max_epochs if epochs is None else epochs) + 1):
        network.train()
        order = train[rng.permutation(train.size)]
        for start in range(0, order.size, int(model.batch_size)):
            batch = torch.from_numpy(order[start : start + int(model.batch_size)])
            if batch.numel() < 2 and order.size >= 2:
                continue  # batch normalisation needs two instances
            optimiser.zero_grad()
            loss = loss_of(network(sequences[batch], others[batch]), targets[batch])
            loss.backward()
            optimiser.step()
        if valid.size == 0:
            best_epoch, best_state = epoch, snapshot()
            continue
        network.eval()
        index = torch.from_numpy(valid)
        with torch.no_grad():
            loss = float(loss_of(network(sequences[index], others[index]), targets[index]))
        if loss < best - 1e-6:
            best, best_epoch, best_state = loss, epoch, snapshot()
        elif epoch - best_epoch >= int(model.patience):
            break
    network.load_state_dict(best_state)
    return network, epoch, best_epoch


#: Fewest groups a validation split holds out whole groups of (else it splits instances).
MIN_GROUPS = 5


def _validation_split(
    y: np.ndarray, fraction: float, seed: int, groups: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Training and validation indices of the training fold: whole groups when there are
    at least :data:`MIN_GROUPS` of them, else instances (stratified for classes)."""
    index = np.arange(len(y))
    n_valid = round(fraction * len(y))
    if fraction <= 0 or len(y) < 10 or n_valid < 1:
        return index, index[:0]
    if groups is not None and np.unique(groups).size >= MIN_GROUPS:
        splitter = GroupShuffleSplit(n_splits=1, test_size=fraction, random_state=seed)
        train, valid = next(splitter.split(index, groups=groups))
        return np.sort(train), np.sort(valid)
    stratify = None
    if y.dtype == np.int64:
        counts = np.bincount(y)
        if counts[counts > 0].min() >= 2 and n_valid >= np.count_nonzero(counts):
            stratify = y
    train, valid = train_test_split(index, test_size=n_valid, random_state=seed, stratify=stratify)
    return np.sort(train), np.sort(valid)
