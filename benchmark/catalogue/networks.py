"""The PyTorch side of the neural sequence models: networks built from plain descriptions.

Only :mod:`benchmark.catalogue.neural` imports this module, inside its estimators' ``fit``
and ``predict``, so that listing the catalogue or starting the CLI never loads PyTorch.

A network is rebuilt from its *architecture*, a dict of plain values that
:func:`benchmark.catalogue.neural.check_architecture` has checked against an allowlist
(known kinds, known keys, bounded sizes), and from its weights in the safetensors format
(a JSON header and raw little-endian arrays: loading them runs no code, unlike
``torch.load`` of a pickle).  Nothing else of a stored model reaches PyTorch.

Every network reads sequences of shape (n, n_channels, length) and the other columns of
the instance, of shape (n, n_others), appended to the learnt features before the output
layer; it returns (n, n_outputs): class scores (logits) or standardised target values.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from typing import Any

import torch
from safetensors.torch import load as load_tensors
from safetensors.torch import save as save_tensors
from torch import nn


class BiLSTM(nn.Module):
    """Bidirectional LSTM over the time steps; the last hidden state of each direction.

    The set-up of the oscillatory-actuation paper (contact localisation from MFCC frames).
    """

    def __init__(self, a: Mapping[str, Any]) -> None:
        super().__init__()
        self.lstm = nn.LSTM(
            input_size=a["n_channels"],
            hidden_size=a["hidden"],
            num_layers=a["layers"],
            batch_first=True,
            bidirectional=True,
            dropout=a["dropout"] if a["layers"] > 1 else 0.0,
        )
        self.dropout = nn.Dropout(a["dropout"])
        self.out = nn.Linear(2 * a["hidden"] + a["n_others"], a["n_outputs"])

    def forward(self, sequences: torch.Tensor, others: torch.Tensor) -> torch.Tensor:
        _, (hidden, _) = self.lstm(sequences.transpose(1, 2))  # (n, length, n_channels) in
        last = torch.cat([hidden[-2], hidden[-1]], dim=1)  # forward and backward directions
        return self.out(torch.cat([self.dropout(last), others], dim=1))


class CNN1D(nn.Module):
    """Three convolution blocks over time (the slip paper's CNN3 over channels), global
    average pooling, one hidden dense layer.

    Each block: convolution (``filters``, then twice as many), ReLU, max pooling by 2
    while the sequence is long enough.
    """

    def __init__(self, a: Mapping[str, Any]) -> None:
        super().__init__()
        widths = (a["n_channels"], a["filters"], 2 * a["filters"], 2 * a["filters"])
        blocks: list[nn.Module] = []
        length = a["length"]
        for before, after in itertools.pairwise(widths):
            blocks += [nn.Conv1d(before, after, a["kernel"], padding="same"), nn.ReLU()]
            if length >= 4:
                blocks.append(nn.MaxPool1d(2))
                length //= 2
        self.features = nn.Sequential(*blocks)
        self.hidden = nn.Sequential(
            nn.Linear(widths[-1] + a["n_others"], a["hidden"]), nn.ReLU(), nn.Dropout(a["dropout"])
        )
        self.out = nn.Linear(a["hidden"], a["n_outputs"])

    def forward(self, sequences: torch.Tensor, others: torch.Tensor) -> torch.Tensor:
        pooled = self.features(sequences).mean(dim=2)
        return self.out(self.hidden(torch.cat([pooled, others], dim=1)))


class _Residual(nn.Module):
    """Three convolutions with batch normalisation, and a shortcut.

    Kernels 7, 5 and 3 (Wang et al. use 8, 5, 3; an odd kernel pads "same" without a copy).
    """

    def __init__(self, before: int, after: int) -> None:
        super().__init__()
        layers: list[nn.Module] = []
        for i, kernel in enumerate((7, 5, 3)):
            layers += [
                nn.Conv1d(before if i == 0 else after, after, kernel, padding="same"),
                nn.BatchNorm1d(after),
            ]
            if i < 2:
                layers.append(nn.ReLU())
        self.body = nn.Sequential(*layers)
        self.shortcut = nn.Sequential(nn.Conv1d(before, after, 1), nn.BatchNorm1d(after))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return torch.relu(self.body(x) + self.shortcut(x))


class ResNet1D(nn.Module):
    """Wang et al.'s (2017) time-series ResNet: three residual blocks of ``filters``,
    twice and twice as many filters, global average pooling, the output layer."""

    def __init__(self, a: Mapping[str, Any]) -> None:
        super().__init__()
        widths = (a["n_channels"], a["filters"], 2 * a["filters"], 2 * a["filters"])
        self.blocks = nn.Sequential(*(_Residual(b, w) for b, w in itertools.pairwise(widths)))
        self.out = nn.Linear(widths[-1] + a["n_others"], a["n_outputs"])

    def forward(self, sequences: torch.Tensor, others: torch.Tensor) -> torch.Tensor:
        pooled = self.blocks(sequences).mean(dim=2)
        return self.out(torch.cat([pooled, others], dim=1))


class _Inception(nn.Module):
    """One inception module: a 1x1 bottleneck, three convolutions of ``kernel``, half and a
    quarter of it (odd), and a max-pooled 1x1 branch; their ``4 * filters`` channels
    batch-normalised and rectified."""

    def __init__(self, before: int, filters: int, kernel: int) -> None:
        super().__init__()
        # A one-channel input needs no bottleneck (Fawaz et al. skip it there too).
        self.bottleneck = nn.Conv1d(before, filters, 1, bias=False) if before > 1 else None
        width = filters if before > 1 else before
        kernels = sorted({max(1, (kernel // 2**i) | 1) for i in range(3)}, reverse=True)
        kernels += [kernels[-1]] * (3 - len(kernels))
        self.convolutions = nn.ModuleList(
            nn.Conv1d(width, filters, k, padding="same", bias=False) for k in kernels
        )
        self.pooled = nn.Sequential(
            nn.MaxPool1d(3, stride=1, padding=1), nn.Conv1d(before, filters, 1, bias=False)
        )
        self.normalise = nn.Sequential(nn.BatchNorm1d(4 * filters), nn.ReLU())

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        narrow = x if self.bottleneck is None else self.bottleneck(x)
        branches = [convolution(narrow) for convolution in self.convolutions]
        return self.normalise(torch.cat([*branches, self.pooled(x)], dim=1))


class InceptionTime(nn.Module):
    """Fawaz et al.'s (2020) InceptionTime network: ``layers`` inception modules of
    ``filters`` filters a branch, kernels ``kernel``, ``kernel / 2`` and ``kernel / 4``
    (they use 40, 20, 10; ours are odd to pad "same" without a copy), a shortcut around
    every three modules, global average pooling, the output layer.

    One network, not the paper's ensemble of five: the engine's folds give the spread.
    """

    def __init__(self, a: Mapping[str, Any]) -> None:
        super().__init__()
        width = 4 * a["filters"]
        self.inceptions = nn.ModuleList(
            _Inception(a["n_channels"] if i == 0 else width, a["filters"], a["kernel"])
            for i in range(a["layers"])
        )
        # Shortcut i joins the input of module 3i to the output of module 3i + 2.
        self.shortcuts = nn.ModuleList(
            nn.Sequential(
                nn.Conv1d(a["n_channels"] if i == 0 else width, width, 1, bias=False),
                nn.BatchNorm1d(width),
            )
            for i in range(a["layers"] // 3)
        )
        self.out = nn.Linear(width + a["n_others"], a["n_outputs"])

    def forward(self, sequences: torch.Tensor, others: torch.Tensor) -> torch.Tensor:
        x = residual = sequences
        for i, module in enumerate(self.inceptions):
            x = module(x)
            if i % 3 == 2:
                x = torch.relu(x + self.shortcuts[i // 3](residual))
                residual = x
        return self.out(torch.cat([x.mean(dim=2), others], dim=1))


#: The networks a description may name (``architecture["kind"]``); nothing else is built.
NETWORKS: Mapping[str, type[nn.Module]] = {
    "bilstm": BiLSTM,
    "cnn1d": CNN1D,
    "resnet1d": ResNet1D,
    "inception-time": InceptionTime,
}


def build_network(architecture: Mapping[str, Any]) -> nn.Module:
    """A new network of ``architecture`` (already checked), weights initialised by the
    current seed of PyTorch's generator."""
    return NETWORKS[architecture["kind"]](architecture)


def _holder(networks: Sequence[nn.Module]) -> nn.Module:
    """What names the weights: one network itself (its weights keep the names they had
    before ensembles), several a list (network ``i``'s names begin ``i.``)."""
    return networks[0] if len(networks) == 1 else nn.ModuleList(networks)


def network_bytes(networks: Sequence[nn.Module]) -> bytes:
    """The networks' weights and buffers in the safetensors format."""
    state = _holder(networks).state_dict()
    return bytes(save_tensors({name: value.detach().contiguous() for name, value in state.items()}))


def load_networks(architecture: Mapping[str, Any], weights: bytes) -> list[nn.Module]:
    """The ``architecture["n_networks"]`` networks of ``architecture`` with ``weights``
    (safetensors bytes), in eval mode.

    Raises
    ------
    ValueError
        The weights are not safetensors, or their names or shapes differ from what the
        architecture builds.
    """
    networks = [build_network(architecture) for _ in range(architecture["n_networks"])]
    try:
        state = load_tensors(weights)
        _holder(networks).load_state_dict(state, strict=True)
    except Exception as exc:  # safetensors' own error types, torch's RuntimeError
        raise ValueError(f"the network's weights do not fit its architecture: {exc}") from None
    return [network.eval() for network in networks]
