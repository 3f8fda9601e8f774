"""Processes forked from a preloaded interpreter, so that each does not import again.

Most of a fresh engine worker's start is importing scikit-learn and the catalogue.  A
*zygote* is one fresh interpreter per calling process that imports them once and then forks
every child that process asks for, in a small fraction of that time.  It is started with
``subprocess`` (so it can be started from a multi-threaded service or a daemonic Dask
worker) and stays single-threaded, so that forking it is safe; the calling process, which
may run threads, never forks.

The caller and its zygote talk over a private socket pair (never a path another user could
connect to).  A request names the function the child calls and carries the descriptors it
receives, the file that takes its stderr and the write end of a *status pipe*, plus what a
fresh interpreter would have read when it started: the caller's environment, import path
and working directory.  The zygote answers the child's pid; when the child ends, the zygote
reaps it and writes its exit status (as :attr:`subprocess.Popen.returncode` gives it) into
the status pipe, which :class:`ForkedProcess` reads.  The zygote ends once its caller has
closed the socket or died; its children then notice that their parent has gone, as engine
workers watch theirs (:mod:`benchmark.run.worker`).

If no zygote can be started or reached, :func:`spawn` answers ``None`` and the caller
starts a fresh interpreter instead.
"""

from __future__ import annotations

import atexit
import contextlib
import importlib
import json
import os
import select
import signal
import socket
import struct
import subprocess
import sys
import threading
import time
from collections.abc import Mapping, Sequence
from typing import IO, Any

__all__ = ["ForkedProcess", "spawn"]

#: Longest wait for the zygote's answer: its first answer follows its imports.
ANSWER_TIMEOUT = 120.0
#: Largest request in bytes (an environment and an import path).
LARGEST_REQUEST = 1 << 20
#: Seconds between the zygote's checks that its caller is alive, when nothing arrives.
PARENT_CHECK_INTERVAL = 1.0
#: Seconds a zygote with no child left waits for a request before it ends (and frees its
#: memory: a notebook's kernel lives long); the next request starts another.
IDLE_SECONDS = 120.0
#: Most descriptors a request passes (the child's, its stderr and its status pipe).
MOST_DESCRIPTORS = 16
_PID = struct.Struct("!i")
_ZYGOTE_MAIN = "from touchbench.benchmark.run.zygote import serve; serve()"


class ForkedProcess:
    """A child forked by the zygote, seen as much like :class:`subprocess.Popen` as needed.

    The zygote, not this process, is the child's parent and reaps it: the exit status
    arrives through ``status``, the read end of the child's status pipe.
    """

    def __init__(self, pid: int, status: int) -> None:
        self.pid = pid
        self.returncode: int | None = None
        self._status = status
        self._lock = threading.Lock()  # a run's loop and a stop may both ask

    def poll(self) -> int | None:
        """The exit status if the child has ended, else ``None``; never blocks."""
        return self._read_status(0.0)

    def wait(self, timeout: float | None = None) -> int:
        """Wait for the child to end; :class:`subprocess.TimeoutExpired` after ``timeout``."""
        code = self._read_status(timeout)
        if code is None:
            raise subprocess.TimeoutExpired(f"child {self.pid}", timeout or 0.0)
        return code

    def kill(self) -> None:
        """SIGKILL the child unless it has ended (its pid may then belong to another)."""
        if self.poll() is None:
            with contextlib.suppress(ProcessLookupError):
                os.kill(self.pid, signal.SIGKILL)

    def _read_status(self, timeout: float | None) -> int | None:
        # As Popen.poll: a poll while another thread waits answers at once.
        if not self._lock.acquire(blocking=timeout != 0.0):
            return self.returncode
        try:
            if self.returncode is not None:
                return self.returncode
            # poll, not select: a long-lived caller's descriptors may pass select's 1,024
            waiting = select.poll()
            waiting.register(self._status, select.POLLIN)
            if not waiting.poll(None if timeout is None else timeout * 1000):
                return None
            data = os.read(self._status, _PID.size)
            os.close(self._status)
            # A zygote that died before it could write: the status is lost with it.
            self.returncode = _PID.unpack(data)[0] if len(data) == _PID.size else 255
            return self.returncode
        finally:
            self._lock.release()

    def __del__(self) -> None:
        if self.returncode is None:
            with contextlib.suppress(OSError):
                os.close(self._status)


class _Zygote:
    """This process's handle on its zygote."""

    def __init__(self, environment: Mapping[str, str], preload: Sequence[str]) -> None:
        self.socket, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        arguments = [str(theirs.fileno()), str(IDLE_SECONDS), *preload]
        try:
            self.process = subprocess.Popen(
                [sys.executable, "-c", _ZYGOTE_MAIN, *arguments],
                pass_fds=(theirs.fileno(),),
                stdin=subprocess.DEVNULL,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,  # each child's own stderr says what went wrong
                env=dict(environment),
                start_new_session=True,
            )
        finally:
            theirs.close()
        self.socket.settimeout(ANSWER_TIMEOUT)
        self.owner = os.getpid()

    def spawn(
        self,
        function: str,
        fds: Sequence[int],
        arguments: Sequence[int | str],
        stderr: int,
        environment: Mapping[str, str],
    ) -> ForkedProcess:
        status_read, status_write = os.pipe()
        request = json.dumps(
            {
                "function": function,
                "arguments": list(arguments),
                "environment": dict(environment),
                "path": [str(entry) for entry in sys.path],
                "directory": _working_directory(),
            }
        ).encode()
        try:
            socket.send_fds(self.socket, [request], [*fds, stderr, status_write])
            answer = self.socket.recv(_PID.size)
        except BaseException:
            os.close(status_read)
            raise
        finally:
            os.close(status_write)
        if len(answer) != _PID.size:
            os.close(status_read)
            raise ConnectionError("the zygote ended")
        return ForkedProcess(_PID.unpack(answer)[0], status_read)

    def ended(self) -> bool:
        """Whether the zygote has ended (idle, or killed)."""
        return self.process.poll() is not None

    def close(self) -> None:
        """Let the zygote end (it does once the socket closes)."""
        self.socket.close()
        try:
            self.process.wait(timeout=5.0)
        except subprocess.TimeoutExpired:
            self.kill()

    def kill(self) -> None:
        """End a zygote that failed to answer, so that it forks nothing more."""
        self.socket.close()
        with contextlib.suppress(ProcessLookupError):
            self.process.kill()
        self.process.wait()


def _working_directory() -> str | None:
    """This process's folder, None if it has been deleted (the child then works in the
    zygote's, rather than the zygote being given up for a path it cannot name)."""
    try:
        return os.getcwd()
    except OSError:
        return None


_LOCK = threading.Lock()
_ZYGOTE: _Zygote | None = None


def spawn(
    function: str,
    fds: Sequence[int],
    arguments: Sequence[int | str] = (),
    *,
    stderr: IO[bytes],
    environment: Mapping[str, str],
    preload: Sequence[str] = (),
) -> ForkedProcess | None:
    """Fork a process that calls ``function(*fds, *arguments)`` and exits.

    The process is forked from this process's zygote, which is started if need be.

    Parameters
    ----------
    function : str
        ``"package.module:name"``; its module is imported in the child unless preloaded.
    fds : sequence of int
        Descriptors the child receives (under other numbers, given to ``function``); it
        holds no others but its standard streams.
    arguments : sequence of int or str
        Further arguments of ``function``.
    stderr : file
        The child's standard error (its standard input and output are ``/dev/null``).
    environment : mapping
        The child's environment.  A zygote starts with the first environment given: the
        variables that libraries read once as they load (BLAS and OpenMP thread counts)
        must be the same in every call.
    preload : sequence of str
        Modules the zygote imports once, when it starts.

    Returns
    -------
    ForkedProcess or None
        ``None`` if the zygote could not be started or did not answer: start a fresh
        interpreter instead, with descriptors of its own (a zygote that answered late may
        have forked a child holding these).
    """
    global _ZYGOTE
    with _LOCK:
        try:
            if _ZYGOTE is not None and _ZYGOTE.owner == os.getpid() and _ZYGOTE.ended():
                _ZYGOTE.close()  # idle for too long: reaped here
                _ZYGOTE = None
            if _ZYGOTE is None or _ZYGOTE.owner != os.getpid():
                _ZYGOTE = _Zygote(environment, preload)
            return _ZYGOTE.spawn(function, fds, arguments, stderr.fileno(), environment)
        except BaseException as error:
            # Ctrl-C between a request and its answer included: an answer left unread would
            # be taken as the next request's, so this zygote is not asked again
            if _ZYGOTE is not None and _ZYGOTE.owner == os.getpid():
                _ZYGOTE.kill()
            _ZYGOTE = None
            if isinstance(error, (OSError, ValueError)):
                return None
            raise


@atexit.register
def _close_zygote() -> None:
    with _LOCK:
        if _ZYGOTE is not None and _ZYGOTE.owner == os.getpid():
            _ZYGOTE.close()


# --- the zygote's side ------------------------------------------------------------------


def serve() -> None:
    """The zygote's main loop: import, then fork a child per request until the caller goes.

    Its arguments are the socket's descriptor, the seconds it may stay idle and the modules
    to preload."""
    caller = socket.socket(fileno=int(sys.argv[1]))
    idle = float(sys.argv[2])
    parent = os.getppid()
    for name in sys.argv[3:]:
        with contextlib.suppress(ImportError):  # a child that needs it says why, itself
            importlib.import_module(name)
    # SIGCHLD wakes the loop through this pipe, so that ended children are reaped at once.
    wake_read, wake_write = os.pipe()
    os.set_blocking(wake_write, False)
    signal.set_wakeup_fd(wake_write)
    signal.signal(signal.SIGCHLD, lambda *_: None)
    statuses: dict[int, int] = {}
    # poll, not select: the socket keeps the caller's number for it, which may pass 1,024
    waiting = select.poll()
    for fd in (caller.fileno(), wake_read):
        waiting.register(fd, select.POLLIN)
    last_activity = time.monotonic()
    while os.getppid() == parent:
        ready = {fd for fd, _ in waiting.poll(PARENT_CHECK_INTERVAL * 1000)}
        if wake_read in ready:
            with contextlib.suppress(BlockingIOError):
                os.read(wake_read, 4096)
        if _reap(statuses):
            last_activity = time.monotonic()
        if not ready and not statuses and time.monotonic() - last_activity > idle:
            break
        if caller.fileno() not in ready:
            continue
        try:
            request, fds, _, _ = socket.recv_fds(caller, LARGEST_REQUEST, MOST_DESCRIPTORS)
        except InterruptedError:
            continue
        if not request:
            break  # the caller closed the socket or died
        last_activity = time.monotonic()
        *given, stderr, status = fds
        pid = os.fork()
        if pid == 0:
            _become_child(json.loads(request), given, stderr)
        for fd in (*given, stderr):
            os.close(fd)
        statuses[pid] = status
        try:
            caller.send(_PID.pack(pid))
        except OSError:
            break


def _reap(statuses: dict[int, int]) -> int:
    """Write the exit status of every ended child into its status pipe; how many ended."""
    ended = 0
    while statuses:
        try:
            pid, status = os.waitpid(-1, os.WNOHANG)
        except ChildProcessError:
            break
        if pid == 0:
            break
        write = statuses.pop(pid, None)
        if write is not None:
            ended += 1
            with contextlib.suppress(OSError):
                os.write(write, _PID.pack(os.waitstatus_to_exitcode(status)))
            os.close(write)
    return ended


def _become_child(request: dict[str, Any], given: list[int], stderr: int) -> None:
    """In the forked child: look like a fresh interpreter, call the function, exit."""
    code = 1
    try:
        os.setsid()
        signal.set_wakeup_fd(-1)
        signal.signal(signal.SIGCHLD, signal.SIG_DFL)
        os.dup2(stderr, 2)
        _close_all_but(given)
        os.environ.clear()
        os.environ.update(request["environment"])
        sys.path[:] = request["path"]
        if request["directory"] is not None:
            with contextlib.suppress(OSError):
                os.chdir(request["directory"])
        _reseed_numpy()
        module, name = request["function"].split(":")
        getattr(importlib.import_module(module), name)(*given, *request["arguments"])
        code = 0
    except SystemExit as exit_:
        code = exit_.code if isinstance(exit_.code, int) else 1
    except BaseException:
        import traceback

        traceback.print_exc()
    finally:
        _exit(code)


def _close_all_but(kept: Sequence[int]) -> None:
    """Close every descriptor above stderr but ``kept``, as ``subprocess`` does for a child:
    the zygote's socket, other children's status pipes, anything a library opened."""
    low = 3
    for fd in sorted(kept):
        os.closerange(low, fd)
        low = fd + 1
    os.closerange(low, os.sysconf("SC_OPEN_MAX"))


def _reseed_numpy() -> None:
    """Give the child its own NumPy global random state, as a fresh interpreter has."""
    numpy = sys.modules.get("numpy")
    if numpy is not None:
        numpy.random.seed()


def _exit(code: int) -> None:
    """End the child as an interpreter would (exit handlers, flushed output), not unwinding
    into the zygote's loop."""
    with contextlib.suppress(BaseException):
        atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(BaseException):
            stream.flush()
    os._exit(code)
