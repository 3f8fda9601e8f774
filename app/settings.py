"""Settings of touchbench, from ``TOUCHBENCH_*`` environment variables, and the service's
trust settings read from them: its API keys with their roles, the host names it answers
and the web origins it accepts changes from."""

from __future__ import annotations

import ipaddress
import re
import stat
import tempfile
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property, lru_cache
from pathlib import Path
from typing import Literal, cast
from urllib.parse import urlsplit

from pydantic import Field, SecretStr
from pydantic_settings import BaseSettings, SettingsConfigDict

from touchbench.app.environment import DEFAULT_DATABASE_URL, ENV_PREFIX
from touchbench.app.errors import AppError

#: What a key may do, each role including the ones before it: ``read`` every GET;
#: ``predict`` also predictions (JSON, file, the live WebSocket) and uploads of data sets
#: and recording sessions; ``write`` everything (runs, training, renaming, cancelling,
#: resuming, deleting).
Role = Literal["read", "predict", "write"]
ROLES: tuple[Role, ...] = ("read", "predict", "write")

#: The shortest key the service accepts.
MIN_KEY_LENGTH = 16

#: Host names the service always answers: the loopback ones.
LOOPBACK_HOSTS = ("127.0.0.1", "localhost", "[::1]")

_KEY_NAME = re.compile(r"[A-Za-z0-9_.-]{1,64}")
_HOST_NAME = re.compile(r"[a-z0-9]([a-z0-9.-]{0,251}[a-z0-9])?")


class SettingsError(AppError):
    """A setting that the service cannot start with (one line naming the variable)."""


@dataclass(frozen=True)
class ApiKey:
    """One key the service knows: its name (for the log), its role and the key itself."""

    name: str
    role: Role
    secret: bytes = field(repr=False)

    def may(self, role: Role) -> bool:
        """Whether this key's role includes ``role``."""
        return ROLES.index(self.role) >= ROLES.index(role)


class Settings(BaseSettings):
    """Every setting of the CLI and the service (``TOUCHBENCH_`` + the name, upper case).

    Attributes
    ----------
    database_url : str
        SQLAlchemy URL of the store; SQLite in the current directory by default.
    api_key : SecretStr or None
        When set, every request but ``GET /healthz`` and the OpenAPI document needs a key
        in the ``X-API-Key`` header; this one is a ``write`` key named ``default``.  At
        least 16 characters.  Without any key the service listens on loopback only.
    api_keys : str or None
        More keys with names and roles: ``name:role:key`` entries separated by commas, or
        the path of a file readable by its owner alone with one ``name role key`` a line
        (lines starting with ``#`` are comments).  Roles: :data:`ROLES`.
    allowed_hosts : str
        Host names or addresses (comma-separated) the service answers besides the loopback
        ones; the ``Host`` header of every request must name one of them.  Required when
        the service listens beyond loopback.
    allowed_origins : str
        Web origins (``scheme://host:port``, comma-separated) whose pages may change the
        store and call the API from a browser (CORS); the service's own origin always may.
    max_upload_mb : float
        Largest upload (data set, recording session, file to predict), enforced while the
        body streams in.
    max_targets : int
        Most targets a data set may have, at import, upload and extraction (default
        1,000: MEKA's largest benchmark data sets have fewer).
    max_attributes : int
        Most attributes (targets and features) a data set may have (default 20,000).
    job_workers : int
        Jobs (runs, extractions, trainings) carried out at once on this host for the store,
        each in a worker process of its own (one service process dispatches them, however
        many ``touchbench serve --workers`` starts).
    run_jobs : int
        Engine worker processes per run.
    dask_scheduler : str or None
        ``tcp://host:port`` of a Dask scheduler: runs' tasks go there instead.
    resume_on_start : bool
        Put runs interrupted by a crash back in the queue when the service starts.
    work_dir : Path
        Where uploaded recording sessions wait for their extraction job.
    model_cache : int
        Loaded models kept in memory per service process for predictions.
    live_follow_seconds : float
        How often a live WebSocket session on ``NAME@ALIAS`` (or ``NAME``) asks the store
        which version its reference names now (one indexed query); 0: before every block.
    """

    model_config = SettingsConfigDict(env_prefix=ENV_PREFIX, extra="ignore")

    database_url: str = DEFAULT_DATABASE_URL
    api_key: SecretStr | None = None
    api_keys: SecretStr | None = None
    allowed_hosts: str = ""
    allowed_origins: str = ""
    max_upload_mb: float = Field(default=200.0, gt=0)
    max_targets: int = Field(default=1000, ge=1)
    max_attributes: int = Field(default=20000, ge=2)
    job_workers: int = Field(default=1, ge=1)
    run_jobs: int = Field(default=1, ge=1)
    dask_scheduler: str | None = None
    resume_on_start: bool = False
    work_dir: Path = Field(default_factory=lambda: Path(tempfile.gettempdir()) / "touchbench")
    model_cache: int = Field(default=8, ge=1)
    live_follow_seconds: float = Field(default=1.0, ge=0, le=3600)

    @property
    def max_upload_bytes(self) -> int:
        return int(self.max_upload_mb * 2**20)

    @cached_property
    def keyring(self) -> tuple[ApiKey, ...]:
        """Every key the service knows (none: the service needs no key).

        Raises
        ------
        SettingsError
            A key is empty or short, a name or key is given twice, a role is unknown, or
            the key file cannot be read or is readable by others than its owner.
        """
        keys: list[ApiKey] = []
        if self.api_key is not None:
            keys.append(_key("TOUCHBENCH_API_KEY", "default", "write", self.api_key))
        if self.api_keys is not None:
            keys.extend(_keys(self.api_keys.get_secret_value()))
        names = [key.name for key in keys]
        for name in names:
            if names.count(name) > 1:
                raise SettingsError(f"TOUCHBENCH_API_KEYS: the key name '{name}' is used twice")
        if len({key.secret for key in keys}) < len(keys):
            raise SettingsError("TOUCHBENCH_API_KEYS: two keys are the same; keys must differ")
        return tuple(keys)

    @cached_property
    def hosts(self) -> frozenset[str]:
        """The host names the service answers (lower case, IPv6 addresses in brackets):
        the loopback ones and :attr:`allowed_hosts`."""
        listed = _listed(
            "TOUCHBENCH_ALLOWED_HOSTS",
            self.allowed_hosts,
            _host,
            "a host name or address (give names without scheme or port, comma-separated)",
        )
        return listed | frozenset(LOOPBACK_HOSTS)

    @cached_property
    def origins(self) -> frozenset[str]:
        """The web origins listed in :attr:`allowed_origins`, as :func:`origin` writes them."""
        return _listed(
            "TOUCHBENCH_ALLOWED_ORIGINS",
            self.allowed_origins,
            origin,
            "an origin (scheme://host[:port], comma-separated)",
        )

    def check_trust(self) -> None:
        """Read the keys, hosts and origins once, so that a bad one stops the service
        before it starts.

        Raises
        ------
        SettingsError
            One of them cannot be used (see :attr:`keyring`, :attr:`hosts`,
            :attr:`origins`).
        """
        self.keyring  # noqa: B018
        self.hosts  # noqa: B018
        self.origins  # noqa: B018


def host_name(header: str) -> str | None:
    """The host name of a ``Host`` header (``name[:port]``, ``[v6]:port``), lower case; None
    when it is not one."""
    header = header.strip().lower()
    if header.startswith("["):
        end = header.find("]")
        name, rest = header[: end + 1], header[end + 1 :]
    else:
        name, _, port = header.partition(":")
        rest = ":" + port if _ else ""
    if rest and not (rest.startswith(":") and rest[1:].isdigit()):
        return None
    return _host(name)


def origin(value: str) -> str | None:
    """``scheme://host[:port]`` in one spelling (lower case, no default port, IPv6 in
    brackets), for comparing origins; None when ``value`` is not an http(s) origin (``null``
    and anything with a path, query or user)."""
    try:
        parts = urlsplit(value.strip())
        port = parts.port
    except ValueError:
        return None
    if parts.scheme not in ("http", "https") or parts.hostname is None:
        return None
    if parts.path not in ("", "/") or parts.query or parts.fragment or parts.username:
        return None
    host = _host(parts.hostname)
    if host is None:
        return None
    if port is None or port == {"http": 80, "https": 443}[parts.scheme]:
        return f"{parts.scheme}://{host}"
    return f"{parts.scheme}://{host}:{port}"


def _host(name: str) -> str | None:
    """``name`` as the service compares host names, or None when it is not one."""
    name = name.strip().lower()
    bare = name[1:-1] if name.startswith("[") and name.endswith("]") else name
    try:
        address = ipaddress.ip_address(bare)
    except ValueError:
        return name if _HOST_NAME.fullmatch(name) else None
    return f"[{address}]" if address.version == 6 else str(address)


def _entries(value: str) -> list[str]:
    return [entry.strip() for entry in value.split(",") if entry.strip()]


def _listed(
    variable: str, value: str, normal: Callable[[str], str | None], what: str
) -> frozenset[str]:
    """The comma-separated entries of ``value``, each as ``normal`` writes it.

    Raises
    ------
    SettingsError
        ``normal`` finds an entry is not ``what`` it should be.
    """
    found = set()
    for entry in _entries(value):
        written = normal(entry)
        if written is None:
            raise SettingsError(f"{variable}: '{entry[:100]}' is not {what}")
        found.add(written)
    return frozenset(found)


def _key(where: str, name: str, role: str, secret: SecretStr | str) -> ApiKey:
    text = secret.get_secret_value() if isinstance(secret, SecretStr) else secret
    if not _KEY_NAME.fullmatch(name):
        raise SettingsError(
            f"{where}: the key name '{name[:64]}' must be letters, digits, '_', '.' or '-'"
        )
    if role not in ROLES:
        raise SettingsError(
            f"{where}: key '{name}' has the role '{role[:32]}'; roles are {', '.join(ROLES)}"
        )
    if not text:
        raise SettingsError(f"{where}: key '{name}' is empty; give a key of at least 16 characters")
    if len(text) < MIN_KEY_LENGTH or any(character.isspace() for character in text):
        raise SettingsError(
            f"{where}: key '{name}' is {len(text)} characters long or holds spaces; a key "
            f"is at least {MIN_KEY_LENGTH} characters without spaces"
        )
    return ApiKey(name, cast(Role, role), text.encode())


def _keys(value: str) -> list[ApiKey]:
    """The keys of ``TOUCHBENCH_API_KEYS``: ``name:role:key`` entries or a key file."""
    where = "TOUCHBENCH_API_KEYS"
    if not value.strip():
        raise SettingsError(f"{where}: empty; give name:role:key entries or a key file")
    if ":" not in value.split(",", 1)[0]:
        return _key_file(Path(value.strip()).expanduser())
    keys = []
    for number, entry in enumerate(_entries(value), 1):
        parts = entry.split(":", 2)
        if len(parts) != 3:
            raise SettingsError(f"{where}: entry {number} is not name:role:key")
        keys.append(_key(where, *parts))
    return keys


def _key_file(path: Path) -> list[ApiKey]:
    where = f"TOUCHBENCH_API_KEYS file {path.name}"
    try:
        mode = path.stat().st_mode
        if not stat.S_ISREG(mode):
            raise SettingsError(f"{where}: not a file")
        if mode & 0o077:
            raise SettingsError(
                f"{where}: readable or writable by others than its owner (mode "
                f"{stat.S_IMODE(mode):o}); make it private with chmod 600"
            )
        text = path.read_text(encoding="utf-8")
    except OSError as error:
        raise SettingsError(f"{where}: cannot be read ({error.strerror})") from None
    except UnicodeDecodeError:
        raise SettingsError(f"{where}: not UTF-8 text") from None
    keys = []
    for number, line in enumerate(text.splitlines(), 1):
        words = line.split()
        if not words or words[0].startswith("#"):
            continue
        if len(words) != 3:
            raise SettingsError(f"{where}:{number}: expected 'name role key'")
        keys.append(_key(f"{where}:{number}", *words))
    if not keys:
        raise SettingsError(f"{where}: holds no key")
    return keys


@lru_cache(maxsize=1)
def get_settings() -> Settings:
    return Settings()
