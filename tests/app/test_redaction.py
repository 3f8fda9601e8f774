"""The logging filter that hides keys: every form a key takes in a log record (message,
arguments, a WebSocket frame, a traceback), and the records' shape kept for the
formatters that read their arguments (uvicorn's access log)."""

from __future__ import annotations

import logging
import sys
from dataclasses import dataclass
from enum import Enum

import pytest
from uvicorn.logging import AccessFormatter

from touchbench.app.redaction import HIDDEN, RedactKeys, install, redact

KEY = "lab-key-0123456789abcdef"


@pytest.mark.parametrize(
    ("text", "shown"),
    [
        ("< x-api-key: anything-at-all", "< x-api-key: ***"),
        ("X-API-Key:whatever", "X-API-Key:***"),
        ("(b'x-api-key', b'sent-key')", "(b'x-api-key', b'***')"),
        ("{'x-api-key': 'sent-key', 'host': 'h'}", "{'x-api-key': '***', 'host': 'h'}"),
        ('{"samplerate": 8000, "api_key": "sent key"}', '{"samplerate": 8000, "api_key": "***"}'),
        (
            "GET /api/runs?api_key=sent&limit=2 HTTP/1.1",
            "GET /api/runs?api_key=***&limit=2 HTTP/1.1",
        ),
        ("query_string: b'apikey=sent'", "query_string: b'apikey=***'"),
        (f"anywhere {KEY}, even mid-word:x{KEY}y", "anywhere ***, even mid-word:x***y"),
        ("require_api_key, check_api_key(settings)", "require_api_key, check_api_key(settings)"),
    ],
)
def test_every_form_of_a_key_is_hidden(text: str, shown: str) -> None:
    assert redact(text, [KEY]) == shown


class _Opcode(Enum):
    TEXT = 1


@dataclass
class _Frame:
    """As the WebSocket library logs a frame: its text cut in the middle."""

    opcode: _Opcode
    data: bytes

    def __str__(self) -> str:
        text = self.data.decode()
        return f"TEXT '{text[:12]}...{text[-20:]}' [{len(self.data)} bytes]"


def _record(msg: object, *args: object) -> logging.LogRecord:
    return logging.LogRecord("uvicorn.error", logging.DEBUG, __file__, 1, msg, args, None)


def test_a_frame_holding_a_key_is_shown_by_kind_and_size() -> None:
    """A frame's cut text may show a key's tail without its label: the whole is hidden."""
    header = b'{"samplerate": 44100, "channels": 1, "api_key": "' + KEY.encode() + b'"}'
    record = _record("< %s", _Frame(_Opcode.TEXT, header))
    assert RedactKeys().filter(record)
    assert record.getMessage() == f"< TEXT [{len(header)} bytes, with a key: not shown]"
    plain = _Frame(_Opcode.TEXT, b'{"samplerate": 44100, "channels": 1, "format": "S16LE"}')
    record = _record("< %s", plain)
    RedactKeys([KEY]).filter(record)
    assert record.args == (plain,)  # untouched: nothing to hide


def test_a_label_and_its_value_in_two_arguments_are_hidden() -> None:
    """The WebSocket library logs a handshake's headers as ``"< %s: %s", name, value``."""
    record = _record("< %s: %s", "x-api-key", "a-key-this-service-never-gave")
    RedactKeys([KEY]).filter(record)
    assert record.getMessage() == "< x-api-key: ***"
    record = _record("sent x-api-key: %s (%d bytes)", "a-key-this-service-never-gave", 29)
    RedactKeys([KEY]).filter(record)
    assert record.getMessage() == "sent x-api-key: *** (29 bytes)"


def test_the_access_log_keeps_its_arguments() -> None:
    """uvicorn's access formatter reads the record's five arguments by position."""
    record = logging.LogRecord(
        "uvicorn.access",
        logging.INFO,
        __file__,
        1,
        '%s - "%s %s HTTP/%s" %d',
        ("127.0.0.1:5000", "GET", f"/api/runs?api_key={KEY}&x=1", "1.1", 401),
        None,
    )
    RedactKeys([KEY]).filter(record)
    fields = '%(client_addr)s - "%(request_line)s" %(status_code)s'
    line = AccessFormatter(fields, use_colors=False).format(record)
    assert line == '127.0.0.1:5000 - "GET /api/runs?api_key=***&x=1 HTTP/1.1" 401 Unauthorized'


def test_a_traceback_and_a_message_given_as_an_object_are_hidden() -> None:
    try:
        raise ValueError(f"refused {KEY}")
    except ValueError:
        record = logging.LogRecord(
            "touchbench.api", logging.ERROR, __file__, 1, "failed", (), sys.exc_info()
        )
    RedactKeys([KEY]).filter(record)
    assert record.exc_text is not None and f"refused {HIDDEN}" in record.exc_text
    assert KEY not in logging.Formatter().format(record)
    record = _record({"x-api-key": KEY})
    RedactKeys().filter(record)
    assert record.getMessage() == "{'x-api-key': '***'}"


def test_install_covers_every_handler_once_and_adds_keys(
    caplog: pytest.LogCaptureFixture,
) -> None:
    logger = logging.getLogger("touchbench.test_redaction")
    handler = logging.StreamHandler()
    logger.addHandler(handler)
    try:
        install([KEY])
        install(["another-key-0123456789"])
        [hiding] = [f for f in handler.filters if isinstance(f, RedactKeys)]
        assert hiding.secrets == {KEY, "another-key-0123456789"}
        with caplog.at_level(logging.INFO, logger="touchbench.test_redaction"):
            logger.info("sent %s", "another-key-0123456789")
        assert "another-key" not in caplog.text and "sent ***" in caplog.text
    finally:
        logger.removeHandler(handler)
        _uninstall()


def _uninstall() -> None:
    """Take the filters :func:`install` put on this process's handlers away again."""
    loggers = [logging.getLogger(), *logging.Logger.manager.loggerDict.values()]
    handlers = [h for lg in loggers if isinstance(lg, logging.Logger) for h in lg.handlers]
    for handler in [*handlers, logging.lastResort]:
        for hiding in [f for f in getattr(handler, "filters", ()) if isinstance(f, RedactKeys)]:
            handler.removeFilter(hiding)
