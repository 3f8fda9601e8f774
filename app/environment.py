"""The ``TOUCHBENCH_*`` environment variables' prefix, the store's default URL, and the one
setting every command needs read without pydantic-settings.

:class:`app.settings.Settings` reads every setting with pydantic-settings, which imports
asyncio, argparse and its cloud providers' sources; a command of the CLI needs only the
store's URL, which :func:`database_url` reads as pydantic-settings does.
"""

from __future__ import annotations

import os

#: Prefix of every setting's environment variable: ``TOUCHBENCH_DATABASE_URL``, ...
ENV_PREFIX = "TOUCHBENCH_"
#: The store when no URL is given: ``touchbench.db`` in the current directory.
DEFAULT_DATABASE_URL = "sqlite:///touchbench.db"


def database_url() -> str:
    """``TOUCHBENCH_DATABASE_URL``, else :data:`DEFAULT_DATABASE_URL`.

    The name is matched in any case, as pydantic-settings matches it
    (:attr:`app.settings.Settings.database_url` holds the same value).
    """
    wanted = f"{ENV_PREFIX}database_url".lower()
    found = [value for name, value in os.environ.items() if name.lower() == wanted]
    return found[-1] if found else DEFAULT_DATABASE_URL
