"""touchbench: which classifier recognises a touch best, from recordings to live predictions.

The one import name of the distribution.  Its parts live in the repository's top-level
folders and install as its subpackages:

``touchbench.features``   signal arrays -> feature arrays, event detection, streaming
``touchbench.drivers``    sources of signal blocks: files, bags, sound cards, simulators
``touchbench.benchmark``  data sets, ARFF/CSV, the catalogue, cross-validation, statistics
``touchbench.app``        the store, the services, the CLI, the REST service, the web page

Importing ``touchbench`` itself imports none of them.  Its Python API
(:mod:`touchbench.app.python`: ``touchbench.bench``, ``.extract``, ``.train``,
``.simulate``, ``.Leaderboard``, ``.Client``, ``.ServiceError``) is imported when first
used.
"""

from __future__ import annotations

# Nothing is imported here, not even typing: Ctrl-C while Python loads this package, before
# the CLI can hear it, would print a traceback. __init__.pyi gives type checkers the names.

#: The Python API, loaded when first used (``import touchbench`` stays cheap): name -> module.
#: No import of them here, not even for type checkers: every part of touchbench imports
#: this package, and the adapters must not import each other through it.
_LAZY = {
    "bench": "touchbench.app.python.api",
    "extract": "touchbench.app.python.api",
    "train": "touchbench.app.python.api",
    "simulate": "touchbench.app.python.api",
    "Leaderboard": "touchbench.app.python.leaderboard",
    "Client": "touchbench.app.python.client",
    "ServiceError": "touchbench.app.python.errors",
}

__all__ = ["Client", "Leaderboard", "ServiceError", "bench", "extract", "simulate", "train"]


def __getattr__(name: str) -> object:
    """``touchbench.bench`` and the rest of the Python API, imported on first use."""
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'touchbench' has no attribute '{name}'")
    import importlib

    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *_LAZY])
