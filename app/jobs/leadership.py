"""Which service process on a host dispatches for a store: the one holding its address.

The address is an abstract Unix socket named after the store; the kernel releases it when
its process ends, kill -9 included, and another process takes it at its next look.  The
holder listens on it, and a wake-up is a connection to it: the others queue work and wake
the holder that way.  Abstract sockets have no permissions, so anyone on the host can take
an address: a process finding it held by another user's process dispatches for itself.
"""

from __future__ import annotations

import contextlib
import hashlib
import logging
import math
import os
import select
import socket
import struct
import sys
import threading
import time
from pathlib import Path

from sqlalchemy.engine import make_url

log = logging.getLogger("touchbench.jobs")

#: Seconds between checks of who holds the dispatch address, by the processes that do not.
HOLDER_CHECK = 10.0


def address_for(url: str) -> str | None:
    """The abstract Unix socket address naming the store at ``url`` on this host, or None
    where every service process dispatches for itself: not Linux (no abstract sockets), or
    an in-memory SQLite store (one per process).

    SQLite files are named by their absolute path, so two stores with the same relative
    URL in different folders are two stores.
    """
    parsed = make_url(url)
    if parsed.get_backend_name() == "sqlite":
        if parsed.database in (None, "", ":memory:") or "mode=memory" in str(parsed):
            return None
        parsed = parsed.set(database=str(Path(parsed.database).resolve()))
    if not sys.platform.startswith("linux"):
        return None
    key = parsed.render_as_string(hide_password=False).encode()
    return "\0touchbench-dispatch-" + hashlib.sha256(key).hexdigest()[:32]


class Leadership:
    """One process's side of the election for an address.

    Parameters
    ----------
    address : str or None
        From :func:`address_for`; None: this process always dispatches.
    name : str
        What the address stands for, in log lines (a store's URL without its password).
    """

    def __init__(self, address: str | None, name: str) -> None:
        self.address = address
        self.name = name
        self._inbox: socket.socket | None = None
        self._woken = threading.Event()
        self._holder_ours = True  # whether the address's holder runs as this user
        self._holder_checked = -math.inf  # time.monotonic() of the last check

    @property
    def leading(self) -> bool:
        """Whether this process holds the address (or needs none)."""
        return self.address is None or self._inbox is not None

    def dispatches(self) -> bool:
        """Whether this process should dispatch now: it holds the address, takes it now, or
        finds it held by another user's process."""
        return self.leading or self._take() or not self._trust_holder()

    def wake(self) -> None:
        """End the current :meth:`wait` of this process and of the address's holder."""
        self._woken.set()
        if self.address is not None:
            with (
                contextlib.suppress(OSError),
                socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as caller,
            ):
                caller.setblocking(False)
                caller.connect(self.address)  # the holder's select sees the connection

    def wait(self, timeout: float) -> None:
        """Wait up to ``timeout`` seconds for a wake-up."""
        if self._inbox is None:
            self._woken.wait(timeout)
            self._woken.clear()
            return
        ready, _, _ = select.select([self._inbox], [], [], timeout)
        while ready:
            try:
                self._inbox.accept()[0].close()
            except BlockingIOError:
                break
        self._woken.clear()

    def release(self) -> None:
        """Give the address up (another process takes it at its next look)."""
        if self._inbox is not None:
            self._inbox.close()
            self._inbox = None

    def _take(self) -> bool:
        """Take the address if no other process on this host holds it."""
        assert self.address is not None  # else this process always leads
        inbox = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        try:
            inbox.bind(self.address)
            inbox.listen(64)
        except OSError:
            inbox.close()
            return False
        inbox.setblocking(False)
        self._inbox = inbox
        log.info("dispatching for %s", self.name)
        return True

    def _trust_holder(self) -> bool:
        """Whether the process holding the address dispatches for this one: it runs as this
        user (checked every ``HOLDER_CHECK`` seconds)."""
        if time.monotonic() - self._holder_checked >= HOLDER_CHECK:
            ours = self._holder_is_ours()
            if self._holder_ours and not ours:
                log.warning("another user holds the dispatch address: dispatching from here")
            self._holder_ours, self._holder_checked = ours, time.monotonic()
        return self._holder_ours

    def _holder_is_ours(self) -> bool:
        """Whether the process holding the address runs as this user (one that cannot be
        reached is not trusted)."""
        assert self.address is not None
        with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as probe:
            probe.settimeout(1.0)
            try:
                probe.connect(self.address)
                credentials = probe.getsockopt(
                    socket.SOL_SOCKET, socket.SO_PEERCRED, struct.calcsize("3i")
                )
            except OSError:
                return False
        _, uid, _ = struct.unpack("3i", credentials)
        return bool(uid == os.getuid())
