"""One Pydantic response model per resource, used by the CLI's ``--json`` and the API alike,
so that the same object reads the same wherever it comes from.

Each resource has its module (``datasets``, ``runs``, ``models``, ``extraction``, ...);
models derive from :class:`Schema`, whose JSON turns NaN and infinities into ``null``.
"""

from touchbench.app.schemas.base import Schema

__all__ = ["Schema"]
