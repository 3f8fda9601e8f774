"""Reading WEKA ARFF text into a :class:`~benchmark.dataset.Dataset`.

The syntax is WEKA's own (``weka.core.converters.ArffLoader``): tokens are separated by
whitespace and commas, ``%`` starts a comment outside quotes, values may be quoted with
``'`` or ``"`` and use Java's backslash escapes inside quotes, an unquoted ``?`` is a
missing value, and a row is either dense (``v1,v2,...``) or sparse (``{i v, j w}``),
optionally followed by an instance weight ``{w}``.

Rows without double quotes, backslashes, braces or comments (nearly every row of a
real data set) take a fast path: split on commas and converted one column at a time.
Any row the fast path cannot take on its own goes through the full tokenizer, which is
also what reports errors, so both paths accept exactly the same files.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from datetime import UTC, date, datetime
from pathlib import Path
from typing import Protocol

import numpy as np

from benchmark.dataset import Attribute, Dataset, Schema, resolve_targets
from benchmark.errors import ConfigurationError, DataFormatError

TargetSpec = int | Sequence[str] | None

# WEKA's tokenizer treats every character up to the space, and the comma, as a separator.
_SEPARATORS = "".join(map(chr, range(0x21))) + ","
_WORD = r"""[^\x00-\x20,{}'"%]+"""
_TOKEN = re.compile(
    r"""[\x00-\x20,]*(?:
      (?P<quoted>'[^'\\]*(?:\\.[^'\\]*)*'|"[^"\\]*(?:\\.[^"\\]*)*")
    | (?P<brace>[{}])
    | (?P<word>"""
    + _WORD
    + r""")
    | (?P<unterminated>['"])
    | (?P<comment>%.*)
    )""",
    re.VERBOSE | re.DOTALL,
)
_PLAIN_WORD = re.compile(_WORD)
_ESCAPE = re.compile(r"\\(?:([0-3][0-7]{0,2}|[4-7][0-7]?)|(.))", re.DOTALL)
_JAVA_ESCAPES = {"a": "\a", "b": "\b", "f": "\f", "n": "\n", "r": "\r", "t": "\t", "v": "\v"}
# A row that contains none of these can be split on commas (see _simple_block).
_NOT_SIMPLE = re.compile(r"""["\\{}%]""")
_CONTROL = re.compile(r"[\x00-\x08\x0e-\x1f\x7f]")
_BLOCK_ROWS = 2048
_LABELS_SHOWN = 10

WORD, QUOTED, OPEN, CLOSE = range(4)
Token = tuple[int, str]


class _LineError(Exception):
    """A problem found inside one line, before the caller knows the file and line number.

    Parameters
    ----------
    message : str
        What is wrong.
    attribute : str, optional
        The attribute concerned.
    """

    def __init__(self, message: str, attribute: str | None = None) -> None:
        super().__init__(message)
        self.message = message
        self.attribute = attribute


# --------------------------------------------------------------------------- text files


def read_text_file(path: str | os.PathLike[str]) -> tuple[str, str]:
    """Read and decode a text file, translating I/O problems into DataFormatError.

    Parameters
    ----------
    path : str or path-like
        The file to read.

    Returns
    -------
    text : str
        The decoded text (see :func:`decode_text`).
    source : str
        The file name as given, for error messages.
    """
    source = os.fspath(path)
    try:
        data = Path(source).read_bytes()
    except FileNotFoundError:
        raise DataFormatError("no such file", source=source) from None
    except IsADirectoryError:
        raise DataFormatError("is a directory, not a file", source=source) from None
    except OSError as error:
        raise DataFormatError(f"cannot read the file: {error.strerror}", source=source) from None
    return decode_text(data, source=source), source


def decode_text(data: str | bytes, *, source: str) -> str:
    """Decode a text file: UTF-8 (BOM ignored), UTF-16 with a BOM, else Latin-1.

    Parameters
    ----------
    data : str or bytes
        The file's content; a ``str`` is only checked.
    source : str
        The file name, for error messages.

    Returns
    -------
    str
        The text without a leading BOM.

    Raises
    ------
    DataFormatError
        If the file is empty (or only whitespace) or is not a text file.
    """
    if isinstance(data, bytes):
        if data.startswith((b"\xff\xfe", b"\xfe\xff")):
            try:
                text = data.decode("utf-16")
            except UnicodeDecodeError:
                raise DataFormatError("not a text file (invalid UTF-16)", source=source) from None
        elif b"\x00" in data:
            raise DataFormatError("not a text file (it contains NUL bytes)", source=source)
        else:
            try:
                text = data.decode("utf-8")
            except UnicodeDecodeError:
                text = data.decode("latin-1")
    else:
        text = data
    text = text.removeprefix("\ufeff")
    if not text.strip():
        raise DataFormatError("empty file", source=source)
    sample = text[:65536]
    if "\x00" in sample or len(_CONTROL.findall(sample)) > len(sample) // 100:
        raise DataFormatError("not a text file (it contains control characters)", source=source)
    return text


def split_lines(text: str) -> list[str]:
    """The lines of ``text``, with ``\\r\\n``, ``\\r`` and ``\\n`` all ending a line."""
    if "\r" in text:
        text = text.replace("\r\n", "\n").replace("\r", "\n")
    return text.split("\n")


# ------------------------------------------------------------------------------ tokens


def tokenize(line: str) -> list[Token]:
    """Split one line into WEKA tokens.

    Parameters
    ----------
    line : str
        One line, without its line break.

    Returns
    -------
    list of (kind, text)
        ``kind`` is WORD (unquoted text), QUOTED (text between quotes, escapes
        decoded), OPEN or CLOSE (a brace).  Separators and comments are dropped.

    Raises
    ------
    _LineError
        On a quote that is not closed on the same line.
    """
    tokens: list[Token] = []
    for quoted, brace, word, unterminated, _comment in _TOKEN.findall(line):
        if word:
            tokens.append((WORD, word))
        elif quoted:
            inner = quoted[1:-1]
            tokens.append((QUOTED, unescape(inner) if "\\" in inner else inner))
        elif brace:
            tokens.append((OPEN if brace == "{" else CLOSE, brace))
        elif unterminated:
            column = next(
                match.start("unterminated") + 1
                for match in _TOKEN.finditer(line)
                if match.lastgroup == "unterminated"
            )
            raise _LineError(
                f"unterminated quote: the {unterminated} at column {column} is not closed"
            )
        else:
            break
    return tokens


def unescape(text: str) -> str:
    """Decode Java's backslash escapes as WEKA's tokenizer does.

    ``\\n \\t \\r \\b \\f \\a \\v`` and octal ``\\ooo`` are control characters; a
    backslash before any other character stands for that character (``\\'``, ``\\"``,
    ``\\\\``, ``\\%``).
    """
    return _ESCAPE.sub(_unescape_one, text)


def _unescape_one(match: re.Match[str]) -> str:
    octal, other = match.groups()
    if octal is not None:
        return chr(int(octal, 8))
    return _JAVA_ESCAPES.get(other, other)


def _describe(token: Token) -> str:
    return f"'{token[1]}'"


def _shortlist(labels: Sequence[str]) -> str:
    shown = ", ".join(labels[:_LABELS_SHOWN])
    if len(labels) > _LABELS_SHOWN:
        shown += f", ... ({len(labels)} in all)"
    return "{" + shown + "}"


# -------------------------------------------------------------------------------- dates

DEFAULT_DATE_FORMAT = "yyyy-MM-dd'T'HH:mm:ss"
_DATE_LETTERS = "yMdHmsSZX"
_MONTHS = (
    "January",
    "February",
    "March",
    "April",
    "May",
    "June",
    "July",
    "August",
    "September",
    "October",
    "November",
    "December",
)
_MONTH_NUMBERS = {
    **{name.lower(): i + 1 for i, name in enumerate(_MONTHS)},
    **{name[:3].lower(): i + 1 for i, name in enumerate(_MONTHS)},
}
_EPOCH_ORDINAL = date(1970, 1, 1).toordinal()
_DateElement = str | tuple[str, int]


class DateFormat:
    """A Java ``SimpleDateFormat`` pattern, parsed and formatted in UTC.

    Supported: the letters ``y M d H m s S`` (``MMM`` and ``MMMM`` for English month
    names; ``S`` counts milliseconds, as in Java), the zone letters ``Z`` and ``X``
    (any offset is read; UTC is written), text in single quotes (``''`` for a quote)
    and any other non-letter character as itself.  Numeric fields that abut another
    numeric field (``yyyyMMdd``) have exactly as many digits as letters.

    Parameters
    ----------
    pattern : str or None
        The pattern; ``None`` for WEKA's default ``yyyy-MM-dd'T'HH:mm:ss``.

    Raises
    ------
    ValueError
        If the pattern uses an unsupported letter or does not close a quote.
    """

    def __init__(self, pattern: str | None = None) -> None:
        self.pattern = DEFAULT_DATE_FORMAT if pattern is None else pattern
        self._elements = _date_elements(self.pattern)
        self._regex = re.compile(_date_regex(self._elements), re.IGNORECASE)

    def parse(self, text: str) -> float:
        """Seconds since the Unix epoch (UTC) of a date written in this format.

        Raises
        ------
        ValueError
            If ``text`` does not match the pattern or names an impossible date.
        """
        match = self._regex.fullmatch(text.strip())
        if match is None:
            raise ValueError(f"'{text}' does not match the date format '{self.pattern}'")
        fields = {"y": 1970, "M": 1, "d": 1, "H": 0, "m": 0, "s": 0, "S": 0}
        offset = 0
        for position, element in enumerate(self._elements):
            if isinstance(element, str):
                continue
            letter, count = element
            value = match.group(f"f{position}")
            if letter in "ZX":
                offset = _zone_offset(value)
            elif letter == "M" and count >= 3:
                month = _MONTH_NUMBERS.get(value.lower())
                if month is None:
                    raise ValueError(
                        f"'{text}' is not a valid date for the format '{self.pattern}': "
                        f"'{value}' is not a month name"
                    )
                fields["M"] = month
            elif letter == "y" and count == 2 and len(value) == 2:
                fields["y"] = _two_digit_year(int(value))
            else:
                fields[letter] = int(value)
        for letter, name, top in (
            ("H", "hour", 23),
            ("m", "minute", 59),
            ("s", "second", 59),
            ("S", "millisecond", 999),
        ):
            if fields[letter] > top:
                raise ValueError(
                    f"'{text}' is not a valid date for the format '{self.pattern}': "
                    f"{name} {fields[letter]} is out of range 0..{top}"
                )
        try:
            days = date(fields["y"], fields["M"], fields["d"]).toordinal() - _EPOCH_ORDINAL
        except ValueError as error:
            raise ValueError(
                f"'{text}' is not a valid date for the format '{self.pattern}': {error}"
            ) from None
        seconds = days * 86400 + fields["H"] * 3600 + fields["m"] * 60 + fields["s"] - offset
        return seconds + fields["S"] / 1000

    def format(self, seconds: float) -> str:
        """``seconds`` since the Unix epoch written in this format (UTC).

        Raises
        ------
        ValueError
            If the date falls outside the years 1 to 9999.
        """
        if not math.isfinite(seconds):
            raise ValueError(f"{seconds} seconds is not a date")
        whole, millisecond = divmod(round(seconds * 1000), 1000)
        days, rest = divmod(whole, 86400)
        try:
            day = date.fromordinal(_EPOCH_ORDINAL + days)
        except (ValueError, OverflowError):
            raise ValueError(f"{seconds} seconds is outside the years 1 to 9999") from None
        hour, rest = divmod(rest, 3600)
        minute, second = divmod(rest, 60)
        numbers = {"d": day.day, "H": hour, "m": minute, "s": second, "S": millisecond}
        parts = []
        for element in self._elements:
            if isinstance(element, str):
                parts.append(element)
                continue
            letter, count = element
            if letter == "y":
                parts.append(f"{day.year % 100:02d}" if count == 2 else f"{day.year:0{count}d}")
            elif letter == "M":
                if count >= 4:
                    parts.append(_MONTHS[day.month - 1])
                elif count == 3:
                    parts.append(_MONTHS[day.month - 1][:3])
                else:
                    parts.append(f"{day.month:0{count}d}")
            elif letter == "Z":
                parts.append("+0000")
            elif letter == "X":
                parts.append("Z")
            else:
                parts.append(f"{numbers[letter]:0{count}d}")
        return "".join(parts)


def _date_elements(pattern: str) -> list[_DateElement]:
    """Literal strings and (letter, count) fields of a SimpleDateFormat pattern."""
    elements: list[_DateElement] = []
    literal: list[str] = []
    i = 0
    while i < len(pattern):
        char = pattern[i]
        if char == "'":
            if pattern.startswith("''", i):
                literal.append("'")
                i += 2
                continue
            i += 1
            while True:
                if i >= len(pattern):
                    raise ValueError(f"date format '{pattern}' does not close a quote")
                if pattern.startswith("''", i):
                    literal.append("'")
                    i += 2
                elif pattern[i] == "'":
                    i += 1
                    break
                else:
                    literal.append(pattern[i])
                    i += 1
        elif char.isascii() and char.isalpha():
            if char not in _DATE_LETTERS:
                raise ValueError(
                    f"date format '{pattern}': the letter '{char}' is not supported "
                    "(supported: y M d H m s S Z X and 'quoted text')"
                )
            end = i
            while end < len(pattern) and pattern[end] == char:
                end += 1
            if literal:
                elements.append("".join(literal))
                literal = []
            elements.append((char, end - i))
            i = end
        else:
            literal.append(char)
            i += 1
    if literal:
        elements.append("".join(literal))
    return elements


def _is_numeric_field(element: _DateElement) -> bool:
    return (
        not isinstance(element, str)
        and element[0] not in "ZX"
        and not (element[0] == "M" and element[1] >= 3)
    )


def _date_regex(elements: list[_DateElement]) -> str:
    parts = []
    for position, element in enumerate(elements):
        if isinstance(element, str):
            parts.append(re.escape(element))
            continue
        letter, count = element
        group = f"(?P<f{position}>"
        if letter in "ZX":
            parts.append(group + r"Z|[+-]\d{2}(?::?\d{2})?)")
        elif letter == "M" and count >= 3:
            parts.append(group + "[A-Za-z]+)")
        else:
            abuts = position + 1 < len(elements) and _is_numeric_field(elements[position + 1])
            parts.append(group + (rf"\d{{{count}}})" if abuts else r"\d+)"))
    return "".join(parts)


def _zone_offset(text: str) -> int:
    """Seconds east of UTC of ``Z``, ``+hh``, ``+hhmm`` or ``+hh:mm``."""
    if text in ("Z", "z"):
        return 0
    digits = text[1:].replace(":", "")
    hours, minutes = int(digits[:2]), int(digits[2:] or 0)
    if hours > 23 or minutes > 59:
        raise ValueError(f"time zone offset '{text}' is out of range")
    return (hours * 3600 + minutes * 60) * (-1 if text[0] == "-" else 1)


def _two_digit_year(value: int) -> int:
    """Java's rule for ``yy``: the year within 80 years before and 20 after now."""
    start = datetime.now(UTC).year - 80
    year = start - start % 100 + value
    return year + 100 if year < start else year


# -------------------------------------------------------------------------------- header


@dataclass
class _Header:
    relation: str | None = None
    relation_line: int = 0
    attributes: list[Attribute] = field(default_factory=list)
    data_line: int = 0  # 1-based line number of @data


def _parse_header(lines: list[str], source: str) -> _Header:
    header = _Header()
    names: set[str] = set()
    for index, line in enumerate(lines):
        number = index + 1
        if not line.strip():
            continue
        try:
            tokens = tokenize(line)
            if not tokens:
                continue
            kind, text = tokens[0]
            keyword = text.lower() if kind == WORD else ""
            if keyword == "@relation":
                if header.relation is not None:
                    raise _LineError("a second @relation")
                header.relation = _relation_name(tokens)
                header.relation_line = number
            elif keyword in ("@attribute", "@data", "@end") and header.relation is None:
                raise _LineError(
                    f"no @relation before {text}: an ARFF file starts with '@relation <name>'"
                )
            elif keyword == "@attribute":
                attribute = _attribute(tokens)
                if attribute.name in names:
                    raise _LineError("duplicate attribute name", attribute.name)
                names.add(attribute.name)
                header.attributes.append(attribute)
            elif keyword == "@data":
                if len(tokens) > 1:
                    raise _LineError(f"unexpected {_describe(tokens[1])} after @data")
                if not header.attributes:
                    raise _LineError("no attributes: @data comes before any @attribute")
                header.data_line = number
                return header
            elif keyword == "@end":
                raise _LineError("@end outside a relational attribute")
            elif header.relation is None:
                raise _LineError(
                    f"no @relation: expected '@relation <name>', found {_describe(tokens[0])}"
                )
            else:
                raise _LineError(f"expected @attribute or @data, found {_describe(tokens[0])}")
        except _LineError as problem:
            raise DataFormatError(
                problem.message, source=source, line=number, attribute=problem.attribute
            ) from None
    if header.relation is None:
        raise DataFormatError("no @relation: this is not an ARFF file", source=source)
    if not header.attributes:
        raise DataFormatError("no attributes and no @data section", source=source)
    raise DataFormatError("no @data section after the attributes", source=source)


def _relation_name(tokens: list[Token]) -> str:
    if len(tokens) < 2 or tokens[1][0] not in (WORD, QUOTED):
        raise _LineError("@relation needs a name")
    if len(tokens) > 2:
        raise _LineError(
            f"unexpected {_describe(tokens[2])} after the relation name "
            "(quote a name that contains spaces)"
        )
    return tokens[1][1]


def _attribute(tokens: list[Token]) -> Attribute:
    if len(tokens) < 2 or tokens[1][0] not in (WORD, QUOTED):
        raise _LineError("@attribute needs a name and a type")
    name = tokens[1][1]
    if len(tokens) < 3:
        raise _LineError("@attribute needs a type after the name", name)
    kind, text = tokens[2]
    if kind == OPEN:
        labels, end = _nominal_labels(tokens, name)
        attribute = Attribute(name, "nominal", labels, "nominal")
    elif kind == WORD and text.lower() in ("numeric", "real", "integer"):
        attribute, end = Attribute(name, "numeric", (), text), 3
    elif kind == WORD and text.lower() == "string":
        attribute, end = Attribute(name, "string", (), text), 3
    elif kind == WORD and text.lower() == "date":
        pattern = None
        end = 3
        if len(tokens) > 3 and tokens[3][0] in (WORD, QUOTED):
            pattern = tokens[3][1]
            end = 4
        try:
            DateFormat(pattern)
        except ValueError as error:
            raise _LineError(str(error), name) from None
        attribute = Attribute(name, "date", (), text, pattern)
    elif kind == WORD and text.lower() == "relational":
        raise _LineError("relational attributes are not supported", name)
    else:
        raise _LineError(
            f"unknown attribute type {_describe(tokens[2])} (expected numeric, real, "
            "integer, string, date or a {list, of, nominal, values})",
            name,
        )
    if len(tokens) > end:
        raise _LineError(f"unexpected {_describe(tokens[end])} after the attribute type", name)
    return attribute


def _nominal_labels(tokens: list[Token], name: str) -> tuple[tuple[str, ...], int]:
    labels: list[str] = []
    seen: set[str] = set()
    for position in range(3, len(tokens)):
        kind, text = tokens[position]
        if kind == CLOSE:
            return tuple(labels), position + 1
        if kind == OPEN:
            raise _LineError("'{' inside a list of nominal values", name)
        if text in seen:
            raise _LineError(f"nominal value '{text}' is declared twice", name)
        seen.add(text)
        labels.append(text)
    raise _LineError("the list of nominal values has no closing '}'", name)


# ------------------------------------------------------------------------------ columns


class _Column(Protocol):
    name: str

    def decode(self, text: str) -> float:
        """The code of one unquoted, non-missing value; raises _LineError."""

    def decode_pieces(self, pieces: Sequence[str]) -> np.ndarray | None:
        """Codes of comma-split pieces of simple rows, ``None`` if any needs the tokenizer.

        Must not change the column's state when it returns ``None``.
        """

    def attribute(self) -> Attribute:
        """The attribute as read (string attributes get their string table)."""


def _simple_text(piece: str) -> str | None:
    """The value of a comma-split piece of a simple row; ``None`` if it needs the tokenizer.

    A missing value gives ``"?"``; since a quoted ``'?'`` gives ``None`` the two differ.
    """
    piece = piece.strip(_SEPARATORS)
    if piece.startswith("'"):
        if len(piece) >= 2 and piece.endswith("'") and "'" not in piece[1:-1]:
            return piece[1:-1] if piece != "'?'" else None
        return None
    return piece if _PLAIN_WORD.fullmatch(piece) else None


@dataclass
class _NumericColumn:
    name: str
    declared: Attribute

    def decode(self, text: str) -> float:
        try:
            return float(text)
        except ValueError:
            raise _LineError(f"'{text}' is not a number", self.name) from None

    def decode_pieces(self, pieces: Sequence[str]) -> np.ndarray | None:
        try:
            return np.array(pieces, dtype=np.float64)
        except ValueError:
            pass
        if "?" not in pieces:
            return None
        try:
            return np.array([p if p != "?" else "nan" for p in pieces], dtype=np.float64)
        except ValueError:
            return None

    def attribute(self) -> Attribute:
        return self.declared


@dataclass
class _NominalColumn:
    name: str
    declared: Attribute
    codes: dict[str, float] = field(init=False)
    piece_codes: dict[str, float] = field(init=False)

    def __post_init__(self) -> None:
        labels = self.declared.values
        self.codes = {label: float(i) for i, label in enumerate(labels)}
        self.piece_codes = {"?": np.nan}
        for i, label in enumerate(labels):
            if "'" not in label and "," not in label:
                self.piece_codes[f"'{label}'"] = float(i)
            if label != "?" and _PLAIN_WORD.fullmatch(label):
                self.piece_codes[label] = float(i)

    def decode(self, text: str) -> float:
        code = self.codes.get(text)
        if code is None:
            raise _LineError(
                f"'{text}' is not one of the declared values {_shortlist(self.declared.values)}",
                self.name,
            )
        return code

    def decode_pieces(self, pieces: Sequence[str]) -> np.ndarray | None:
        lookup = self.piece_codes
        try:
            return np.array([lookup[p] for p in pieces])
        except KeyError:
            pass
        try:
            return np.array([lookup[p.strip(_SEPARATORS)] for p in pieces])
        except KeyError:
            return None

    def attribute(self) -> Attribute:
        return self.declared


@dataclass
class _StringColumn:
    name: str
    declared: Attribute
    table: dict[str, int] = field(default_factory=dict)

    def decode(self, text: str) -> float:
        code = self.table.get(text)
        if code is None:
            code = self.table[text] = len(self.table)
        return float(code)

    def decode_pieces(self, pieces: Sequence[str]) -> np.ndarray | None:
        texts = self.texts(pieces)
        return None if texts is None else self.decode_texts(texts)

    @staticmethod
    def texts(pieces: Sequence[str]) -> list[str] | None:
        """First half of :meth:`decode_pieces`: the texts, without touching the table."""
        texts = [_simple_text(piece) for piece in pieces]
        return None if None in texts else texts  # type: ignore[return-value]

    def decode_texts(self, texts: list[str]) -> np.ndarray:
        """Second half of :meth:`decode_pieces`: codes, adding new strings to the table."""
        return np.array([np.nan if text == "?" else self.decode(text) for text in texts])

    def attribute(self) -> Attribute:
        return Attribute(self.name, "string", tuple(self.table), self.declared.declared_type)


@dataclass
class _DateColumn:
    name: str
    declared: Attribute
    date_format: DateFormat = field(init=False)

    def __post_init__(self) -> None:
        self.date_format = DateFormat(self.declared.date_format)

    def decode(self, text: str) -> float:
        try:
            return self.date_format.parse(text)
        except ValueError as error:
            raise _LineError(str(error), self.name) from None

    def decode_pieces(self, pieces: Sequence[str]) -> np.ndarray | None:
        texts = [_simple_text(p) for p in pieces]
        if None in texts:
            return None
        try:
            return np.array(
                [np.nan if t == "?" else self.date_format.parse(t) for t in texts]  # type: ignore[arg-type]
            )
        except ValueError:
            return None

    def attribute(self) -> Attribute:
        return self.declared


def _column(attribute: Attribute) -> _Column:
    if attribute.kind == "numeric":
        return _NumericColumn(attribute.name, attribute)
    if attribute.kind == "nominal":
        return _NominalColumn(attribute.name, attribute)
    if attribute.kind == "string":
        return _StringColumn(attribute.name, attribute)
    return _DateColumn(attribute.name, attribute)


# ---------------------------------------------------------------------------------- rows


def _decode(column: _Column, token: Token) -> float:
    kind, text = token
    if kind == WORD and text == "?":
        return np.nan
    return column.decode(text)


def _weight(tokens: list[Token], start: int) -> float:
    """The instance weight ``{w}`` at ``tokens[start]``, which must end the row."""
    rest = tokens[start:]
    if len(rest) != 3 or rest[0][0] != OPEN or rest[2][0] != CLOSE or rest[1][0] != WORD:
        raise _LineError("after the values a row may only have an instance weight such as {0.5}")
    try:
        weight = float(rest[1][1])
    except ValueError:
        raise _LineError(f"instance weight '{rest[1][1]}' is not a number") from None
    if not weight >= 0:
        raise _LineError(f"instance weight {rest[1][1]} is negative or not a number")
    return weight


def _dense_row(tokens: list[Token], columns: list[_Column]) -> tuple[np.ndarray, float | None]:
    n = len(columns)
    end = next((i for i, token in enumerate(tokens) if token[0] in (OPEN, CLOSE)), len(tokens))
    if end != n:
        raise _LineError(f"expected {n} values, found {end}")
    row = np.array([_decode(column, token) for column, token in zip(columns, tokens, strict=False)])
    weight = _weight(tokens, end) if end < len(tokens) else None
    return row, weight


def _sparse_row(
    tokens: list[Token], columns: list[_Column]
) -> tuple[np.ndarray, float | None, set[int]]:
    """The values and weight of a sparse row, and the indices it gives explicitly."""
    n = len(columns)
    row = np.zeros(n)
    given: set[int] = set()
    previous = -1
    position = 1
    while True:
        if position >= len(tokens):
            raise _LineError("sparse row has no closing '}'")
        kind, text = tokens[position]
        if kind == CLOSE:
            position += 1
            break
        if kind != WORD:
            raise _LineError(f"expected a sparse index, found {_describe(tokens[position])}")
        try:
            index = int(text)
        except ValueError:
            raise _LineError(f"sparse index '{text}' is not an integer") from None
        if not 0 <= index < n:
            raise _LineError(f"sparse index {index} is out of range 0..{n - 1}")
        if index <= previous:
            raise _LineError(f"sparse indices must increase: {index} comes after {previous}")
        if position + 1 >= len(tokens) or tokens[position + 1][0] not in (WORD, QUOTED):
            raise _LineError(f"sparse index {index} has no value", columns[index].name)
        row[index] = _decode(columns[index], tokens[position + 1])
        given.add(index)
        previous = index
        position += 2
    weight = _weight(tokens, position) if position < len(tokens) else None
    return row, weight, given


@dataclass
class _Rows:
    """The data section as it is read: blocks of rows in file order, and their weights."""

    blocks: list[np.ndarray] = field(default_factory=list)
    weights: dict[int, float] = field(default_factory=dict)
    count: int = 0
    sparse: bool = False
    implicit_strings: set[int] = field(default_factory=set)  # string columns left out

    def add_block(self, block: np.ndarray) -> None:
        self.blocks.append(block)
        self.count += block.shape[0]

    def add_row(self, row: np.ndarray, weight: float | None) -> None:
        if weight is not None:
            self.weights[self.count] = weight
        self.add_block(row[np.newaxis, :])


def _parse_data(lines: list[str], first: int, columns: list[_Column], source: str) -> _Rows:
    """Read the rows from ``lines[first:]`` (0-based index of the line after @data)."""
    rows = _Rows()
    simple: list[int] = []  # indices of consecutive simple lines not yet read
    string_indices = [j for j, c in enumerate(columns) if isinstance(c, _StringColumn)]

    def read_simple() -> None:
        block = _simple_block([lines[i] for i in simple], columns)
        if block is None:
            for index in simple:
                read_tokenized(index)
        else:
            rows.add_block(block)
        simple.clear()

    def read_tokenized(index: int) -> None:
        try:
            tokens = tokenize(lines[index])
            if not tokens:
                return
            if tokens[0][0] == OPEN:
                rows.sparse = True
                row, weight, given = _sparse_row(tokens, columns)
                rows.implicit_strings.update(j for j in string_indices if j not in given)
            else:
                row, weight = _dense_row(tokens, columns)
        except _LineError as problem:
            raise DataFormatError(
                problem.message, source=source, line=index + 1, attribute=problem.attribute
            ) from None
        rows.add_row(row, weight)

    for index in range(first, len(lines)):
        line = lines[index]
        if _NOT_SIMPLE.search(line) is None:
            if line.strip():
                simple.append(index)
                if len(simple) >= _BLOCK_ROWS:
                    read_simple()
            continue
        if simple:
            read_simple()
        read_tokenized(index)
    if simple:
        read_simple()
    return rows


def _simple_block(lines: list[str], columns: list[_Column]) -> np.ndarray | None:
    """Rows of non-blank lines without braces, double quotes, backslashes or comments.

    Returns
    -------
    ndarray of shape (len(lines), len(columns)) or None
        ``None`` when some line needs the tokenizer (which then reads or rejects it).
    """
    n = len(columns)
    pieces = [line.split(",") for line in lines]
    if any(len(row) != n for row in pieces):
        return None
    block = np.empty((len(lines), n))
    cells = list(zip(*pieces, strict=True))
    strings: list[tuple[int, _StringColumn, list[str]]] = []
    for j, column in enumerate(columns):
        if isinstance(column, _StringColumn):
            texts = column.texts(cells[j])
            if texts is None:
                return None
            strings.append((j, column, texts))
            continue
        decoded = column.decode_pieces(cells[j])
        if decoded is None:
            return None
        block[:, j] = decoded
    # String tables grow only once the whole block is known to be readable.
    for j, column, texts in strings:
        block[:, j] = column.decode_texts(texts)
    return block


# ------------------------------------------------------------------------------- reading


def loads_arff(
    text: str | bytes, *, source: str = "<string>", targets: TargetSpec = None
) -> Dataset:
    """Parse ARFF text.

    Parameters
    ----------
    text : str or bytes
        The whole file; bytes are decoded as UTF-8, else Latin-1.
    source : str
        Name used in error messages.
    targets : int, sequence of str, or None
        ``None``: MEKA's ``-C`` in the relation name, else the last attribute; ``N``:
        the first N attributes; ``-N``: the last N; names: those attributes.

    Returns
    -------
    Dataset
        ``values`` has shape (n_instances, n_attributes); ``weights`` is ``None`` unless
        some row has an instance weight; ``sparse`` tells whether rows were sparse.

    Raises
    ------
    DataFormatError
        For anything wrong with the text, or targets that do not exist; the error
        carries the source, the 1-based line and the attribute where they apply.
    """
    lines = split_lines(decode_text(text, source=source))
    header = _parse_header(lines, source)
    assert header.relation is not None
    names = [attribute.name for attribute in header.attributes]
    try:
        target_indices = resolve_targets(targets, names, relation=header.relation)
    except ConfigurationError as error:
        line = header.relation_line if targets is None else None
        raise DataFormatError(f"targets: {error}", source=source, line=line) from None
    columns = [_column(attribute) for attribute in header.attributes]
    rows = _parse_data(lines, header.data_line, columns, source)

    values = np.vstack(rows.blocks) if rows.blocks else np.empty((0, len(columns)))
    for j in rows.implicit_strings:
        table = columns[j]
        assert isinstance(table, _StringColumn)
        if not table.table:
            table.decode("")
    weights = None
    if rows.weights:
        weights = np.ones(rows.count)
        weights[list(rows.weights)] = list(rows.weights.values())
    schema = Schema(
        header.relation, tuple(column.attribute() for column in columns), target_indices
    )
    return Dataset(schema, values, weights=weights, sparse=rows.sparse)


def read_arff(path: str | os.PathLike[str], *, targets: TargetSpec = None) -> Dataset:
    """Read an ARFF file.

    Parameters
    ----------
    path : str or path-like
        The file.
    targets : int, sequence of str, or None
        As in :func:`loads_arff`.

    Returns
    -------
    Dataset
        See :func:`loads_arff`.

    Raises
    ------
    DataFormatError
        If the file does not exist, cannot be read, or is not valid ARFF.
    """
    text, source = read_text_file(path)
    return loads_arff(text, source=source, targets=targets)
