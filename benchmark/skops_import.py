"""Importing :mod:`skops.io` without importing every package of scikit-learn.

When it is imported, skops lists the estimators it trusts by default with scikit-learn's
:func:`~sklearn.utils.all_estimators`.  That walks scikit-learn's packages with
:func:`pkgutil.walk_packages`, which imports every package to look inside it, the ones
``all_estimators`` then ignores too: its tests (and pytest with them) and its vendored
array libraries (PyTorch with them).  Every command that stores or loads a model paid for
it.  :func:`import_skops_io` imports skops while ``all_estimators`` walks with
:func:`_public_packages`, which never looks inside a package it would ignore: the same
estimators (a test compares the lists), only the modules ``all_estimators`` reads imported.
"""

from __future__ import annotations

import importlib
import pkgutil
import sys
import threading
import types
from collections.abc import Iterable, Iterator
from typing import Any

__all__ = ["import_skops_io"]

_LOCK = threading.Lock()


def import_skops_io() -> types.ModuleType:
    """:mod:`skops.io`, imported (once) with the lighter walk of scikit-learn."""
    with _LOCK:  # another thread's import may be under way: its module is not whole yet
        if "skops.io" in sys.modules:
            return sys.modules["skops.io"]
        from sklearn.utils import discovery

        walking = discovery.pkgutil
        discovery.pkgutil = types.SimpleNamespace(walk_packages=_public_packages)
        try:
            return importlib.import_module("skops.io")
        finally:
            discovery.pkgutil = walking


def _public_packages(
    path: Iterable[str] | None = None, prefix: str = "", onerror: Any = None
) -> Iterator[pkgutil.ModuleInfo]:
    """Every module under ``path``, as :func:`pkgutil.walk_packages` yields them, without
    importing (or yielding what is below) a package ``all_estimators`` ignores: a private
    one (``._`` in its name) or one of its ``_MODULE_TO_IGNORE``."""
    from sklearn.utils.discovery import _MODULE_TO_IGNORE

    for info in pkgutil.iter_modules(path, prefix):
        yield info
        ignored = "._" in info.name or not _MODULE_TO_IGNORE.isdisjoint(info.name.split("."))
        if info.ispkg and not ignored:
            package = importlib.import_module(info.name)
            yield from _public_packages(package.__path__, info.name + ".")
