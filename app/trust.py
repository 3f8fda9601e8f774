"""Whom the service trusts: keys by name and role, the host names it answers, the web
origins it takes changes from.

The settings (:class:`app.settings.Settings`) hold what the environment says, as text;
this module reads that text once, at start-up (:func:`read_keys`, :func:`read_hosts`,
:func:`read_origins`), and gives the trust boundary (:mod:`app.api.trust`, the key check
of :mod:`app.api.deps`) the rules it applies to every request (:func:`host_name`,
:func:`origin`), so that a name is written the same way where it is configured and where
it is compared.
"""

from __future__ import annotations

import ipaddress
import re
import stat
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal, cast
from urllib.parse import urlsplit

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
#: What a key may hold: what an HTTP header carries unchanged (printable ASCII, no space).
_KEY_TEXT = re.compile(r"[!-~]+")
_HOST_NAME = re.compile(r"[a-z0-9]([a-z0-9.-]{0,251}[a-z0-9])?")


class TrustSettingError(ValueError):
    """A key, host name or origin setting that cannot be used (one line naming the
    variable; :class:`app.settings.Settings` raises it as a settings error)."""


@dataclass(frozen=True)
class ApiKey:
    """One key the service knows: its name (for the log), its role and the key itself."""

    name: str
    role: Role
    secret: bytes = field(repr=False)

    def may(self, role: Role) -> bool:
        """Whether this key's role includes ``role``."""
        return ROLES.index(self.role) >= ROLES.index(role)


def read_keys(api_key: str | None, api_keys: str | None) -> tuple[ApiKey, ...]:
    """Every key the service knows (none: the service needs no key).

    A refusal names the key by where it is given (the variable, the entry's or the line's
    number), never by a value: a key put in the wrong place (a bare key for the list, a key
    and its role swapped) must not reach the terminal or a log.

    Parameters
    ----------
    api_key : str or None
        ``TOUCHBENCH_API_KEY``: a ``write`` key named ``default``.
    api_keys : str or None
        ``TOUCHBENCH_API_KEYS``: ``name:role:key`` entries separated by commas, or the path
        of a key file readable by its owner alone.

    Raises
    ------
    TrustSettingError
        A key is empty, short or cannot be sent as a header, a name or key is given twice,
        a name or role is not one, or the key file cannot be read or is readable by others
        than its owner.
    """
    given: list[tuple[str, ApiKey]] = []
    if api_key is not None:
        where = "TOUCHBENCH_API_KEY"
        given.append((where, _key(where, "default", "write", api_key)))
    if api_keys is not None:
        given.extend(_keys(api_keys))
    for i, (where, key) in enumerate(given):
        for other_where, other in given[:i]:
            if key.name == other.name:
                raise TrustSettingError(
                    f"{where}: the key's name is also {other_where}'s; names must differ"
                )
            if key.secret == other.secret:
                raise TrustSettingError(
                    f"{where}: two keys are the same (this and {other_where}'s); keys must differ"
                )
    return tuple(key for _, key in given)


def read_hosts(value: str) -> frozenset[str]:
    """The host names the service answers (lower case, IPv6 addresses in brackets): the
    loopback ones and those ``TOUCHBENCH_ALLOWED_HOSTS`` (``value``) lists.

    Raises
    ------
    TrustSettingError
        An entry is not a host name or address.
    """
    listed = _listed(
        "TOUCHBENCH_ALLOWED_HOSTS",
        value,
        _host,
        "a host name or address (give names without scheme or port, comma-separated)",
    )
    return listed | frozenset(LOOPBACK_HOSTS)


def read_origins(value: str) -> frozenset[str]:
    """The web origins ``TOUCHBENCH_ALLOWED_ORIGINS`` (``value``) lists, as :func:`origin`
    writes them.

    Raises
    ------
    TrustSettingError
        An entry is not an origin.
    """
    return _listed(
        "TOUCHBENCH_ALLOWED_ORIGINS",
        value,
        origin,
        "an origin (scheme://host[:port], comma-separated)",
    )


def is_loopback(address: str) -> bool:
    """Whether the service listening on ``address`` is reachable from this machine only."""
    if address == "localhost":
        return True
    try:
        return ipaddress.ip_address(address).is_loopback
    except ValueError:
        return False


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
    TrustSettingError
        ``normal`` finds an entry is not ``what`` it should be.
    """
    found = set()
    for entry in _entries(value):
        written = normal(entry)
        if written is None:
            raise TrustSettingError(f"{variable}: '{entry[:100]}' is not {what}")
        found.add(written)
    return frozenset(found)


def _key(where: str, name: str, role: str, text: str) -> ApiKey:
    """The key ``text`` named ``name`` with ``role``, given at ``where``.

    Raises
    ------
    TrustSettingError
        Naming ``where`` and what is wrong, never a value.
    """
    if not _KEY_NAME.fullmatch(name):
        raise TrustSettingError(
            f"{where}: a key's name is 1 to 64 letters, digits, '_', '.' or '-' "
            "(name:role:key, in this order)"
        )
    if role not in ROLES:
        raise TrustSettingError(
            f"{where}: not a role; roles are {', '.join(ROLES)} (name:role:key, in this order)"
        )
    if not text:
        raise TrustSettingError(f"{where}: the key is empty; give a key of at least 16 characters")
    if not _KEY_TEXT.fullmatch(text):
        raise TrustSettingError(
            f"{where}: the key holds a space, a control or a non-ASCII character; a key is "
            "sent as the X-API-Key header: printable ASCII characters only"
        )
    if len(text) < MIN_KEY_LENGTH:
        raise TrustSettingError(
            f"{where}: the key is {len(text)} characters long; a key is at least "
            f"{MIN_KEY_LENGTH} characters"
        )
    return ApiKey(name, cast(Role, role), text.encode())


def _keys(value: str) -> list[tuple[str, ApiKey]]:
    """The keys of ``TOUCHBENCH_API_KEYS`` (``name:role:key`` entries or a key file), each
    with where it is given."""
    where = "TOUCHBENCH_API_KEYS"
    if not value.strip():
        raise TrustSettingError(f"{where}: empty; give name:role:key entries or a key file")
    if ":" not in value.split(",", 1)[0]:
        return _key_file(Path(value.strip()).expanduser())
    keys = []
    for number, entry in enumerate(_entries(value), 1):
        at = f"{where} entry {number}"
        parts = entry.split(":", 2)
        if len(parts) != 3:
            raise TrustSettingError(f"{at}: not name:role:key")
        keys.append((at, _key(at, *parts)))
    return keys


def _key_file(path: Path) -> list[tuple[str, ApiKey]]:
    try:
        mode = path.stat().st_mode
    except (OSError, ValueError) as error:
        # the value is not shown: a bare key given for the list lands here
        reason = error.strerror if isinstance(error, OSError) else "not a path"
        raise TrustSettingError(
            f"TOUCHBENCH_API_KEYS: not name:role:key entries, and the key file it would name "
            f"cannot be read ({reason})"
        ) from None
    where = f"TOUCHBENCH_API_KEYS file {path.name}"
    try:
        if not stat.S_ISREG(mode):
            raise TrustSettingError(f"{where}: not a file")
        if mode & 0o077:
            raise TrustSettingError(
                f"{where}: readable or writable by others than its owner (mode "
                f"{stat.S_IMODE(mode):o}); make it private with chmod 600"
            )
        text = path.read_text(encoding="utf-8")
    except OSError as error:
        raise TrustSettingError(f"{where}: cannot be read ({error.strerror})") from None
    except UnicodeDecodeError:
        raise TrustSettingError(f"{where}: not UTF-8 text") from None
    keys = []
    for number, line in enumerate(text.splitlines(), 1):
        words = line.split()
        if not words or words[0].startswith("#"):
            continue
        at = f"{where} line {number}"
        if len(words) != 3:
            raise TrustSettingError(f"{at}: expected 'name role key'")
        keys.append((at, _key(at, *words)))
    if not keys:
        raise TrustSettingError(f"{where}: holds no key")
    return keys
