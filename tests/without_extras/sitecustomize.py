"""Put on ``PYTHONPATH``: hides the top-level modules that ``HIDE_MODULES_FOR_TEST`` names
(comma-separated) from every import of the process, as if they were not installed.

Python imports ``sitecustomize`` at start-up, so the processes a command or the service
starts (workers, jobs) hide them too.
"""

from __future__ import annotations

import importlib.abc
import os
import sys
from collections.abc import Sequence
from importlib.machinery import ModuleSpec
from types import ModuleType

HIDDEN = frozenset(filter(None, os.environ.get("HIDE_MODULES_FOR_TEST", "").split(",")))


class _Hide(importlib.abc.MetaPathFinder):
    def find_spec(
        self,
        fullname: str,
        path: Sequence[str] | None,
        target: ModuleType | None = None,
    ) -> ModuleSpec | None:
        if fullname.partition(".")[0] in HIDDEN:
            raise ModuleNotFoundError(f"No module named {fullname!r}", name=fullname)
        return None


if HIDDEN:
    sys.meta_path.insert(0, _Hide())
