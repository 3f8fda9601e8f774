"""The ``TOUCHBENCH_*`` environment variables' prefix, the store's variable and default URL,
and the one setting every command needs, read without pydantic-settings.

:class:`app.settings.Settings` reads every setting with pydantic-settings, which imports
asyncio, argparse and its cloud providers' sources; a command of the CLI needs only the
store's URL, which :func:`database_url` reads as pydantic-settings does.
"""

from __future__ import annotations

import os

#: Prefix of every setting's environment variable: ``TOUCHBENCH_DATABASE_URL``, ...
ENV_PREFIX = "TOUCHBENCH_"
#: The variable holding the store's URL.
DATABASE_URL_VARIABLE = f"{ENV_PREFIX}DATABASE_URL"
#: The store when no URL is given: ``touchbench.db`` in the current directory.
DEFAULT_DATABASE_URL = "sqlite:///touchbench.db"


def database_url() -> str:
    """:data:`DATABASE_URL_VARIABLE`'s value, else :data:`DEFAULT_DATABASE_URL`.

    The name is matched in any case, as pydantic-settings matches it
    (:attr:`app.settings.Settings.database_url` holds the same value).
    """
    wanted = DATABASE_URL_VARIABLE.lower()
    found = [value for name, value in os.environ.items() if name.lower() == wanted]
    return found[-1] if found else DEFAULT_DATABASE_URL
