"""touchbench: which classifier recognises a touch best, from recordings to live predictions.

The one import name of the distribution.  Its parts live in the repository's top-level
folders and install as its subpackages:

``touchbench.features``   signal arrays -> feature arrays, event detection, streaming
``touchbench.drivers``    sources of signal blocks: files, bags, sound cards, simulators
``touchbench.benchmark``  data sets, ARFF/CSV, the catalogue, cross-validation, statistics
``touchbench.app``        the store, the services, the CLI, the REST service, the web page

Importing ``touchbench`` itself imports none of them: the Python API's names below load
their module when first used.
"""

from __future__ import annotations

import importlib
from typing import Any

#: The Python API's names, by the module that defines each.  Not imported here, not even for
#: type checkers: every module of the package imports this one (its parent), so an import
#: here would tie the CLI, the service and the web page to the Python adapter.
_LAZY = {
    "Client": "touchbench.app.python.client",
    "ServiceError": "touchbench.app.python.errors",
    "Leaderboard": "touchbench.app.python.leaderboard",
}

__all__ = ["Client", "Leaderboard", "ServiceError"]


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'touchbench' has no attribute '{name}'")
    return getattr(importlib.import_module(module), name)
