"""touchbench's optional parts: which extra brings which library, and the one error when
one is missing.

``pip install touchbench`` installs the core; the rest comes with extras named after what
they bring (``pip install 'touchbench[neural]'``).  Code that needs an optional library
calls :func:`require` before importing it, so that a missing one is a single line naming
the extra to install instead of a ``ModuleNotFoundError`` from deep inside a fit.

>>> EXTRAS["boosting"].modules
('lightgbm', 'catboost')
"""

from __future__ import annotations

import importlib.util
from collections.abc import Iterable
from dataclasses import dataclass
from functools import cache

from touchbench.benchmark.errors import ConfigurationError


@dataclass(frozen=True)
class Extra:
    """One optional part of touchbench.

    Parameters
    ----------
    name : str
        The extra's name in ``pip install 'touchbench[NAME]'``.
    modules : tuple of str
        The top-level modules it installs.
    brings : str
        What it brings, for messages.
    """

    name: str
    modules: tuple[str, ...]
    brings: str

    @property
    def install(self) -> str:
        """The command that installs it."""
        return f"pip install 'touchbench[{self.name}]'"


EXTRAS: dict[str, Extra] = {
    extra.name: extra
    for extra in (
        Extra("neural", ("torch", "safetensors"), "PyTorch, for the neural networks"),
        Extra(
            "onnx",
            ("onnx", "skl2onnx", "onnxmltools", "onnxruntime"),
            "ONNX export and ONNX Runtime",
        ),
        Extra("boosting", ("lightgbm", "catboost"), "LightGBM and CatBoost"),
        Extra("sequences", ("aeon",), "aeon, for MiniRocket and MultiRocket"),
    )
}
#: Each optional module's extra.
EXTRA_OF: dict[str, Extra] = {
    module: extra for extra in EXTRAS.values() for module in extra.modules
}


class MissingExtraError(ConfigurationError):
    """Something asked for needs an optional library that is not installed.

    Parameters
    ----------
    what : str
        What was asked for (``"classifier 'bilstm'"``).
    extra : Extra
    """

    def __init__(self, what: str, extra: Extra) -> None:
        self.what = what
        self.extra = extra
        super().__init__(
            f"{what} needs touchbench's '{extra.name}' extra ({extra.brings}), which is not "
            f"installed: {extra.install}"
        )


@cache
def is_installed(module: str) -> bool:
    """Whether the top-level ``module`` can be imported (found, not imported)."""
    try:
        return importlib.util.find_spec(module) is not None
    except (ImportError, ValueError):
        return False


def missing(modules: Iterable[str]) -> list[str]:
    """The modules of ``modules`` that are not installed, in order."""
    return [module for module in modules if not is_installed(module)]


def extras_of(modules: Iterable[str]) -> list[Extra]:
    """The extras that bring ``modules`` (optional ones), in order, each once."""
    return list(dict.fromkeys(EXTRA_OF[module] for module in modules))


def require(modules: Iterable[str], what: str) -> None:
    """Refuse ``what`` unless every module of ``modules`` (optional ones, of
    :data:`EXTRA_OF`) is installed.

    Raises
    ------
    MissingExtraError
        Naming the extra of the first missing module.
    """
    for module in missing(modules):
        raise MissingExtraError(what, EXTRA_OF[module])
