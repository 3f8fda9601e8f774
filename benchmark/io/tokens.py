"""WEKA's ARFF tokenizer: one line of text into words, quoted strings and braces.

The syntax is WEKA's own (``weka.core.converters.ArffLoader``): tokens are separated by
whitespace and commas (every character up to the space, and the comma), ``%`` starts a
comment outside quotes, values may be quoted with ``'`` or ``"`` and use Java's backslash
escapes inside quotes, and ``{`` ``}`` delimit sparse rows, instance weights and lists of
nominal values.  This module is the exact reference: the faster readers of the data
section must agree with it on every line they accept.
"""

from __future__ import annotations

import re
from collections.abc import Sequence

#: WEKA's separators: every character up to the space, and the comma.
SEPARATORS = "".join(map(chr, range(0x21))) + ","
#: An unquoted word: anything but separators, braces, quotes and ``%``.
WORD_PATTERN = r"""[^\x00-\x20,{}'"%]+"""
_TOKEN = re.compile(
    r"""[\x00-\x20,]*(?:
      (?P<quoted>'[^'\\]*(?:\\.[^'\\]*)*'|"[^"\\]*(?:\\.[^"\\]*)*")
    | (?P<brace>[{}])
    | (?P<word>"""
    + WORD_PATTERN
    + r""")
    | (?P<unterminated>['"])
    | (?P<comment>%.*)
    )""",
    re.VERBOSE | re.DOTALL,
)
_ESCAPE = re.compile(r"\\(?:([0-3][0-7]{0,2}|[4-7][0-7]?)|(.))", re.DOTALL)
_JAVA_ESCAPES = {"a": "\a", "b": "\b", "f": "\f", "n": "\n", "r": "\r", "t": "\t", "v": "\v"}
_LABELS_SHOWN = 10

WORD, QUOTED, OPEN, CLOSE = range(4)
Token = tuple[int, str]


class LineError(Exception):
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
    LineError
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
            raise LineError(
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


def describe(token: Token) -> str:
    """A token as an error message quotes it."""
    return f"'{token[1]}'"


def shortlist(labels: Sequence[str]) -> str:
    """``{a, b, ...}`` with at most ten labels, for error messages."""
    shown = ", ".join(labels[:_LABELS_SHOWN])
    if len(labels) > _LABELS_SHOWN:
        shown += f", ... ({len(labels)} in all)"
    return "{" + shown + "}"
