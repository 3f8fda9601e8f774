"""The ``TOUCHBENCH_*`` environment variables' prefix, and the settings every command of the
CLI reads, read without pydantic-settings.

:class:`app.settings.Settings` declares every setting and reads them with
pydantic-settings, which imports pydantic, asyncio and its cloud providers' sources; a
command of the CLI needs only the store's URL (and, when it fails, the debug switch), which
this module reads as pydantic-settings does (a test holds the two equal).
"""

from __future__ import annotations

import os

#: Prefix of every setting's environment variable: ``TOUCHBENCH_DATABASE_URL``, ...
ENV_PREFIX = "TOUCHBENCH_"
#: The variable holding the store's URL.
DATABASE_URL_VARIABLE = f"{ENV_PREFIX}DATABASE_URL"
#: The store when no URL is given: ``touchbench.db`` in the current directory.
DEFAULT_DATABASE_URL = "sqlite:///touchbench.db"
#: Values of a switch that mean off (pydantic's words of false, in any case, and empty).
FALSE_WORDS = frozenset({"", "0", "off", "f", "false", "n", "no"})


def setting(field: str) -> str | None:
    """The environment's value of the setting ``field`` (``TOUCHBENCH_`` + its name), or
    None when it is not set.

    The name is matched in any case, as pydantic-settings matches it; of two spellings,
    the later in the environment wins, as there.
    """
    wanted = f"{ENV_PREFIX}{field}".lower()
    found = [value for name, value in os.environ.items() if name.lower() == wanted]
    return found[-1] if found else None


def database_url() -> str:
    """:data:`DATABASE_URL_VARIABLE`'s value, else :data:`DEFAULT_DATABASE_URL`
    (:attr:`app.settings.Settings.database_url`)."""
    value = setting("database_url")
    return DEFAULT_DATABASE_URL if value is None else value


def debug() -> bool:
    """Whether ``TOUCHBENCH_DEBUG`` is on (:attr:`app.settings.Settings.debug`): any value
    but the words of :data:`FALSE_WORDS`."""
    value = setting("debug")
    return value is not None and value.lower() not in FALSE_WORDS


def put_setting(field: str, value: str) -> None:
    """Give the setting ``field`` the value ``value`` in this process's environment, and so
    in the processes it starts, in place of any other spelling of its variable."""
    wanted = f"{ENV_PREFIX}{field}".lower()
    for name in [name for name in os.environ if name.lower() == wanted]:
        del os.environ[name]
    os.environ[f"{ENV_PREFIX}{field.upper()}"] = value
