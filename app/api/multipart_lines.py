"""The lines of a multipart/form-data body's text files followed chunk by chunk as the body
streams in, so that a line longer than its reader allows is refused at the chunk where it
passes the limit: the rest is never read, and the form parser that takes the same chunks
has spooled no more than the limit and a chunk.

:class:`MultipartLines` finds the parts' delimiters (a delimiter or a line break may be
split between two chunks), reads each part's headers for its field name and file name, and
asks who reads the file (``choose``): a :class:`LineRule` for a text file, ``None`` for a
recording (WAV, FLAC, a bag), which is never line-checked.  The text is followed with the
bytes methods (``find``, ``rfind``, ``isascii``, ``translate``) and NumPy (line breaks
counted), never a Python loop over its bytes: a chunk costs a few passes in C, far less
than a form parser's.

A rule says what its reader counts (characters or bytes, lines ended by any of ``\\r\\n``,
``\\r`` and ``\\n`` or by ``\\n`` alone), so that the refusal here names the line the reader
would name.  Only what the reader surely refuses is refused here: characters are counted
from below (a UTF-8 lead byte or an ASCII byte is one character, whatever the reader's
encoding), a part holding a NUL byte or starting with a UTF-16 byte-order mark is left to
its reader, and so is the rest of a part that a strict UTF-8 reader could not decode.
"""

from __future__ import annotations

import codecs
import dataclasses
import functools
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Literal

from python_multipart.multipart import parse_options_header

from touchbench.benchmark.io.textfile import (
    UTF8_BOM,
    UTF16_BOMS,
    count_line_ends,
    count_newlines,
)

#: Bytes a text reader decodes past the point where it finds a line too long (what
#: ``io.TextIOWrapper`` reads at a time): a strict UTF-8 reader meets an undecodable byte
#: there before it says the line is too long, so a refusal here waits for that many bytes
#: to decode.
READ_AHEAD = 8192
#: The most bytes of one part's headers: a part with more is not followed (the form parser
#: says what is wrong with it).
MAX_HEADERS = 16 << 10
#: The most bytes of a form field's value kept for :attr:`FilePart.fields`.
FIELD_BYTES = 1024
#: The bytes that continue a UTF-8 character (not counted as characters).
_CONTINUATION = bytes(range(0x80, 0xC0))


@dataclass(frozen=True)
class LineRule:
    """How the reader of a text file bounds its lines, and what it says of a line too long.

    Attributes
    ----------
    limit : int
        A line longer than this (its line break not counted) is refused: a value at which
        the reader surely refuses it.
    refusal : callable
        ``refusal(line)``: the reader's own error for the 1-based ``line``.
    unit : {"chars", "bytes"}
        What the limit counts (characters after decoding, or bytes).
    breaks : {"any", "lf"}
        What ends a line: any of ``\\r\\n``, ``\\r`` and ``\\n`` (a text file opened with
        ``newline=""``), or ``\\n`` alone (a regular expression over the whole text).
    utf8 : bool
        The reader decodes strictly as UTF-8: a part that is not is left to it, and a
        refusal waits for :data:`READ_AHEAD` bytes past the line's limit to decode.
    lines : int, optional
        Only this many first lines are checked (the reader of the rest is not known yet).
    """

    limit: int
    refusal: Callable[[int], Exception]
    unit: Literal["chars", "bytes"] = "chars"
    breaks: Literal["any", "lf"] = "any"
    utf8: bool = False
    lines: int | None = None


@dataclass(frozen=True)
class FilePart:
    """A file of a form, as its headers name it.

    Attributes
    ----------
    field : str
        The form field's name (``file``, ``recordings``).
    filename : str or None
        The client's file name, as the form parser decodes it.
    index : int
        Its place among the files of ``field`` (0 for the first).
    fields : mapping of str to str
        The form's text fields that came before the file (values up to
        :data:`FIELD_BYTES`).
    """

    field: str
    filename: str | None
    index: int = 0
    fields: Mapping[str, str] = dataclasses.field(default_factory=dict)


@dataclass(frozen=True)
class LongLine:
    """A line of a file longer than its reader allows.

    Attributes
    ----------
    part : FilePart
    line : int
        The line's 1-based number.
    error : Exception
        The reader's refusal (:attr:`LineRule.refusal`).
    consumed : int
        Bytes of the body fed when it was found.
    """

    part: FilePart
    line: int
    error: Exception
    consumed: int


#: ``choose(part)``: the rule of the reader of ``part``, None when its lines are not checked.
Chooser = Callable[[FilePart], "LineRule | None"]


class _Lines:
    """The lines of one text part, fed its bytes in order."""

    def __init__(self, rule: LineRule) -> None:
        self.rule = rule
        self.on = True  # False once the rest of the part is left to its reader
        self.line = 1
        self.length = 0  # of the current line so far, in the rule's unit
        self._started = False
        self._held = b""  # the first bytes, while too few to tell a byte-order mark
        self._carriage = False  # the bytes so far end with "\r" (a "\n" next joins it)
        self._decoder = codecs.getincrementaldecoder("utf-8")() if rule.utf8 else None
        self._found: int | None = None  # a line refused, while the read-ahead decodes
        self._ahead = 0  # bytes still to decode before that refusal stands
        self._past = 0  # bytes at least of the last data fed past the line's limit

    def feed(self, data: bytes) -> int | None:
        """The number of the line refused once ``data`` is read, else None."""
        if not self.on or not data:
            return None
        if not self._started:
            data = self._held + data
            if len(data) < len(UTF8_BOM) and _mark_begins(data):
                self._held = data
                return None
            self._started, self._held = True, b""
            if data.startswith(UTF16_BOMS):  # transcoded by some readers: left to them
                self.on = False
                return None
            data = data.removeprefix(UTF8_BOM)
        return self._follow(data)

    def finish(self) -> int | None:
        """The number of the line refused once the part ended, else None."""
        if self._held:  # a part of one or two bytes
            self._started, held, self._held = True, self._held, b""
            line = self._follow(held)
            if line is not None:
                return line
        if not self.on:
            return None
        if self._decoder is not None:
            try:
                self._decoder.decode(b"", final=True)
            except UnicodeDecodeError:
                return None
        return self._found

    def _follow(self, data: bytes) -> int | None:
        if not self.on or not data:
            return None
        if b"\x00" in data or not self._decodes(data):  # not text: its reader says what
            self.on = False
            return None
        if self._found is not None:
            self._ahead -= len(data)
            return self._found if self._ahead <= 0 else None
        line = self._lines(data, self.rule)
        if line is None or self._decoder is None:
            return line
        # decoded up to here; a strict reader decodes a little further before it refuses
        self._found, self._ahead = line, READ_AHEAD - self._past
        return line if self._ahead <= 0 else None

    def _decodes(self, data: bytes) -> bool:
        """Whether ``data`` continues valid UTF-8, for a strict reader (always for others)."""
        if self._decoder is None:
            return True
        if data.isascii() and not self._decoder.getstate()[0]:
            return True
        try:
            self._decoder.decode(data)
        except UnicodeDecodeError:
            return False
        return True

    def _lines(self, data: bytes, rule: LineRule) -> int | None:
        """Follow ``data``'s lines; the number of the first one over the limit, else None."""
        any_break = rule.breaks == "any"
        if self._carriage:  # "\r" ended the bytes before: a "\n" now is the same break
            self._carriage = False
            if data.startswith(b"\n"):
                data = data[1:]
        if not data:
            return None
        # over the limit: the characters past it, a byte each at least, are bytes past it
        first = _first_break(data, any_break)
        if first < 0:
            self.length += _measure(data, rule.unit)
            self._past = self.length - rule.limit - 1
            return self.line if self.length > rule.limit else None
        self.length += _measure(data[:first], rule.unit)
        if self.length > rule.limit:
            self._past = self.length - rule.limit - 1 + len(data) - first
            return self.line
        last = _last_break(data, any_break)
        if last - first - 1 > rule.limit:  # whole lines in between may be over the limit
            inside = _long_inside(data, first, last, rule)
            if inside is not None and (rule.lines is None or self.line + inside <= rule.lines):
                self._past = 0
                return self.line + inside
        self.line += _count_breaks(data, any_break)
        if rule.lines is not None and self.line > rule.lines:
            self.on = False
            return None
        self._carriage = any_break and data.endswith(b"\r")
        self.length = _measure(data[last + 1 :], rule.unit)
        self._past = self.length - rule.limit - 1
        return self.line if self.length > rule.limit else None


def _mark_begins(data: bytes) -> bool:
    """Whether ``data`` may be the start of a byte-order mark."""
    return any(mark.startswith(data) for mark in (UTF8_BOM, *UTF16_BOMS))


def _first_break(data: bytes, any_break: bool) -> int:
    newline = data.find(b"\n")
    if not any_break:
        return newline
    carriage = data.find(b"\r", 0, newline if newline >= 0 else len(data))
    return carriage if carriage >= 0 else newline


def _last_break(data: bytes, any_break: bool) -> int:
    newline = data.rfind(b"\n")
    return max(newline, data.rfind(b"\r", newline + 1)) if any_break else newline


def _count_breaks(data: bytes, any_break: bool) -> int:
    """Line breaks in ``data`` (``\\r\\n`` counts once), as the rule says lines end."""
    return count_line_ends(data) if any_break else count_newlines(data)


def _measure(data: bytes, unit: str) -> int:
    """``data``'s length in ``unit``: characters counted as the bytes that start one."""
    if unit == "bytes" or data.isascii():
        return len(data)
    return len(data.translate(None, _CONTINUATION))


@functools.lru_cache(maxsize=16)
def _long_run(limit: int, any_break: bool) -> re.Pattern[bytes]:
    return re.compile(rb"[^\r\n]{%d,}" % (limit + 1) if any_break else rb"[^\n]{%d,}" % (limit + 1))


def _long_inside(data: bytes, first: int, last: int, rule: LineRule) -> int | None:
    """How many lines past the current one the first line over the limit is, among the
    whole lines between the breaks at ``first`` and ``last``; None if none is.

    Only a chunk longer than the limit can hold such a line: one regular expression finds
    the runs of as many bytes without a break, and only they are measured.
    """
    any_break = rule.breaks == "any"
    for run in _long_run(rule.limit, any_break).finditer(data, first + 1, last):
        if _measure(run.group(), rule.unit) > rule.limit:
            return _count_breaks(data[: run.start()], any_break)
    return None


class MultipartLines:
    """A multipart/form-data body's text files, their lines followed as the body arrives.

    Parameters
    ----------
    boundary : bytes
        The body's boundary (:func:`boundary_of` its content type).
    choose : callable
        ``choose(part)``: the :class:`LineRule` of the reader of a :class:`FilePart`, None
        when its lines are not checked.

    Notes
    -----
    :meth:`feed` takes each chunk as it arrives and answers the first :class:`LongLine`.
    A body this scanner cannot follow (headers too long, no delimiter where one belongs)
    is left alone from there on: the form parser that reads it says what is wrong.
    """

    def __init__(self, boundary: bytes, choose: Chooser) -> None:
        self._choose = choose
        self._delimiter = b"\r\n--" + boundary
        # the body's first delimiter comes without the line break of the others
        self._buffer = b"\r\n"
        self._state: Literal["preamble", "after", "headers", "data", "off"] = "preamble"
        self._fields: dict[str, str] = {}
        self._files: dict[str, int] = {}
        self._part: FilePart | None = None
        self._lines: _Lines | None = None
        self._value: bytearray | None = None  # a text field's value, while it comes
        self._name = ""
        #: Bytes of the body fed so far.
        self.consumed = 0

    def feed(self, chunk: bytes) -> LongLine | None:
        """Follow ``chunk``, the next bytes of the body; the first line found too long."""
        self.consumed += len(chunk)
        if self._state == "off":
            return None
        data = self._buffer + chunk if self._buffer else chunk
        at = 0
        keep = len(self._delimiter) - 1  # a delimiter may begin in the last bytes
        while True:
            if self._state in ("preamble", "data"):
                found = data.find(self._delimiter, at)
                end = found if found >= 0 else max(at, len(data) - keep)
                if self._state == "data":
                    line = self._content(data[at:end])
                    if line is None and found >= 0:
                        line = self._end_part()
                    if line is not None:
                        self._state = "off"
                        return line
                if found < 0:
                    at = end
                    break
                at, self._state = found + len(self._delimiter), "after"
            elif self._state == "after":  # "--" ends the body; else the line ends
                if len(data) - at < 2:
                    break
                if data.startswith(b"--", at):
                    self._state = "off"
                    break
                end = data.find(b"\r\n", at)
                if end < 0:
                    self._give_up_past(len(data) - at, 1024)
                    break
                at, self._state = end + 2, "headers"
            elif self._state == "headers":
                if data.startswith(b"\r\n", at):  # a part without headers
                    end, headers = at, b""
                else:
                    end = data.find(b"\r\n\r\n", at)
                    if end < 0:
                        self._give_up_past(len(data) - at, MAX_HEADERS)
                        break
                    headers = data[at:end]
                at = end + (2 if not headers else 4)
                self._start_part(headers)
                self._state = "data"
            else:
                break
        self._buffer = data[at:] if self._state != "off" else b""
        return None

    def _give_up_past(self, size: int, most: int) -> None:
        if size > most:
            self._state = "off"

    def _start_part(self, headers: bytes) -> None:
        """A part's headers read: a file is given its rule, a text field is kept."""
        name: str | None = None
        filename: str | None = None
        for header in headers.split(b"\r\n"):
            key, _, value = header.partition(b":")
            if key.strip().lower() == b"content-disposition":
                _, options = parse_options_header(value.strip())
                if b"name" in options:
                    name = _decoded(options[b"name"])
                if b"filename" in options:
                    filename = _decoded(options[b"filename"])
        self._part, self._lines, self._value = None, None, None
        self._name = name or ""
        if name is None:
            return
        if filename is None:
            self._value = bytearray()
            return
        index = self._files.get(name, 0)
        self._files[name] = index + 1
        self._part = FilePart(name, filename, index, dict(self._fields))
        rule = self._choose(self._part)
        self._lines = _Lines(rule) if rule is not None else None

    def _content(self, data: bytes) -> LongLine | None:
        if self._lines is not None and self._part is not None:
            line = self._lines.feed(data)
            return self._long(line) if line is not None else None
        if self._value is not None and len(self._value) <= FIELD_BYTES:
            self._value += data[: FIELD_BYTES + 1 - len(self._value)]
        return None

    def _end_part(self) -> LongLine | None:
        if self._lines is not None:
            line = self._lines.finish()
            if line is not None:
                return self._long(line)
        if self._value is not None and len(self._value) <= FIELD_BYTES:
            self._fields[self._name] = _decoded(bytes(self._value))
        self._part, self._lines, self._value = None, None, None
        return None

    def _long(self, line: int) -> LongLine:
        assert self._part is not None and self._lines is not None
        return LongLine(self._part, line, self._lines.rule.refusal(line), self.consumed)


def _decoded(raw: bytes) -> str:
    """A header parameter or field as the form parser decodes it (UTF-8, else Latin-1)."""
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        return raw.decode("latin-1")


def boundary_of(content_type: bytes) -> bytes | None:
    """The boundary of a ``multipart/form-data`` content type, None for any other."""
    kind, options = parse_options_header(content_type)
    if kind.lower() != b"multipart/form-data":
        return None
    boundary = options.get(b"boundary")
    return boundary or None
