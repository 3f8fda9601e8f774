"""Keys out of every log line: a logging filter that hides API keys, at every level.

A key reaches the log by ways the service does not write itself: uvicorn's access log
shows a request's query (``?api_key=...``), and at the debug level the WebSocket
library logs a handshake's headers (``x-api-key: ...``) and every frame, the live
session's header message with its ``api_key`` included.  :class:`RedactKeys` hides, in
every record the handlers it is installed on emit (message, arguments, traceback):

- the service's own keys, wherever they stand;
- whatever follows a key's label (``x-api-key``, ``api_key``, ``api-key``, ``apikey``) as a
  header, a query parameter, a JSON or Python field, right key or wrong;
- the whole payload of a WebSocket frame that holds either (the library shows a frame cut
  in the middle, where a key's tail may stand without its label).

:func:`install` puts it on the handlers of every logger there is when the service starts
(uvicorn's, the service's own, the root logger's and Python's last-resort handler).
"""

from __future__ import annotations

import logging
import re
from collections.abc import Iterable
from typing import Any

#: What stands for a hidden key.
HIDDEN = "***"

#: A key's label (not the end of a longer name), its separator (a header's or a query's
#: after a bare label, a mapping's or a pair's after a quoted one) and the opening quote of
#: its value, if any.
_LABELLED = re.compile(
    r"(?<![\w-])(?P<label>(?:x[-_])?api[-_]?key)"
    r"(?P<sep>\s*[:=]\s*|['\"]\s*[:,]\s*b?)(?P<quote>['\"]?)",
    re.IGNORECASE,
)
#: Where an unquoted value ends: a header's at the end of its line, a query parameter's at
#: the next one.
_UNQUOTED_END = re.compile(r"[\s&'\"]")


def redact(text: str, secrets: Iterable[str] = ()) -> str:
    """``text`` with ``secrets`` and every labelled key's value replaced by :data:`HIDDEN`.

    >>> redact("< x-api-key: abc123")
    '< x-api-key: ***'
    >>> redact('GET /api/runs?api_key=abc&limit=2 {"api_key": "x y"}')
    'GET /api/runs?api_key=***&limit=2 {"api_key": "***"}'
    """
    for secret in secrets:
        if secret:
            text = text.replace(secret, HIDDEN)
    pieces = []
    position = 0
    for found in _LABELLED.finditer(text):
        start = found.end()
        if start < position:  # inside a value already hidden
            continue
        quote = found.group("quote")
        if quote:
            end = text.find(quote, start)
            end = len(text) if end < 0 else end
        else:
            stop = _UNQUOTED_END.search(text, start)
            end = len(text) if stop is None else stop.start()
        if end == start:
            continue
        pieces.append(text[position:start])
        pieces.append(HIDDEN)
        position = end
    pieces.append(text[position:])
    return "".join(pieces)


class RedactKeys(logging.Filter):
    """Hide keys in every record a handler emits (see the module's help).

    Parameters
    ----------
    secrets : iterable of str
        The service's own keys; :meth:`add` gives more.
    """

    def __init__(self, secrets: Iterable[str] = ()) -> None:
        super().__init__()
        self.secrets: set[str] = set()
        self.add(secrets)

    def add(self, secrets: Iterable[str]) -> None:
        self.secrets.update(secret for secret in secrets if secret)

    def filter(self, record: logging.LogRecord) -> bool:
        if not record.args:
            record.msg = self._argument(record.msg)
        else:
            if isinstance(record.args, tuple):
                record.args = tuple(self._argument(arg) for arg in record.args)
            elif isinstance(record.args, dict):
                record.args = {key: self._argument(arg) for key, arg in record.args.items()}
            # a label and its value apart (``"< %s: %s", name, value``, ``"key: %s", key``):
            # the record becomes its message, hidden (the arguments are kept otherwise, for
            # formatters that read them, as uvicorn's access log does)
            try:
                message = record.getMessage()
            except (TypeError, ValueError):  # the caller's arguments do not fit its message
                message = hidden = ""
            else:
                hidden = redact(message, self.secrets)
            if hidden != message:
                record.msg, record.args = hidden, ()
        if record.exc_info and not record.exc_text:
            record.exc_text = logging.Formatter().formatException(record.exc_info)
        if record.exc_text:
            record.exc_text = redact(record.exc_text, self.secrets)
        if record.stack_info:
            record.stack_info = redact(record.stack_info, self.secrets)
        return True

    def _argument(self, arg: Any) -> Any:
        """``arg`` as it may be shown: unchanged when it holds no key, else its text with
        the keys hidden (a frame that holds one: its kind and size only)."""
        if isinstance(arg, int | float) or arg is None:
            return arg
        data = getattr(arg, "data", None)
        if isinstance(data, bytes | bytearray) and hasattr(arg, "opcode"):
            payload = bytes(data).decode("utf-8", "replace")
            if redact(payload, self.secrets) != payload:
                kind = getattr(arg.opcode, "name", "frame")
                return f"{kind} [{len(data)} bytes, with a key: not shown]"
        text = arg.decode("utf-8", "replace") if isinstance(arg, bytes) else str(arg)
        hidden = redact(text, self.secrets)
        return arg if hidden == text else hidden


def install(secrets: Iterable[str]) -> None:
    """Hide ``secrets`` (and every labelled key) in what every handler of every logger
    there is now emits, and in Python's last-resort handler; idempotent, and a second
    call adds its secrets to the filters already installed."""
    secrets = tuple(secrets)
    loggers = [logging.getLogger()] + [
        logger
        for logger in logging.Logger.manager.loggerDict.values()
        if isinstance(logger, logging.Logger)
    ]
    handlers = {id(handler): handler for logger in loggers for handler in logger.handlers}
    if logging.lastResort is not None:
        handlers[id(logging.lastResort)] = logging.lastResort
    for handler in handlers.values():
        present = [f for f in handler.filters if isinstance(f, RedactKeys)]
        if present:
            present[0].add(secrets)
        else:
            handler.addFilter(RedactKeys(secrets))
