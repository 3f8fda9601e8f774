"""The header of an ARFF file: ``@relation``, the ``@attribute`` declarations, ``@data``.

:class:`HeaderParser` takes the file's lines one at a time until ``@data``, so that a
reader can stop there and stream the data section, and so that the first bytes of a file
can be checked before the rest is read.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from touchbench.benchmark.dataset import Attribute
from touchbench.benchmark.errors import DataFormatError
from touchbench.benchmark.io.dates import DateFormat
from touchbench.benchmark.io.tokens import (
    CLOSE,
    OPEN,
    QUOTED,
    WORD,
    LineError,
    Token,
    describe,
    tokenize,
)


@dataclass
class Header:
    """What the header declares.

    Attributes
    ----------
    relation : str or None
        The relation name as written (MEKA's options included).
    relation_line : int
        1-based line of ``@relation``.
    attributes : list of Attribute
        The declared attributes in order (string attributes without their table).
    data_line : int
        1-based line of ``@data``; 0 until it is read.
    """

    relation: str | None = None
    relation_line: int = 0
    attributes: list[Attribute] = field(default_factory=list)
    data_line: int = 0


class HeaderParser:
    """Reads header lines until ``@data``.

    Parameters
    ----------
    source : str
        The file name, for error messages.
    """

    def __init__(self, source: str) -> None:
        self.source = source
        self.header = Header()
        self._names: set[str] = set()

    @property
    def done(self) -> bool:
        """Whether ``@data`` has been read."""
        return self.header.data_line > 0

    def feed(self, line: str, number: int) -> bool:
        """Read one line; ``True`` once it was ``@data``.

        Raises
        ------
        DataFormatError
            For anything wrong on the line, naming the line and the attribute.
        """
        if not line.strip():
            return False
        try:
            self._line(line, number)
        except LineError as problem:
            raise DataFormatError(
                problem.message, source=self.source, line=number, attribute=problem.attribute
            ) from None
        return self.done

    def finish(self) -> Header:
        """The header once ``@data`` was read.

        Raises
        ------
        DataFormatError
            When the file ended before ``@data``.
        """
        if self.done:
            return self.header
        if self.header.relation is None:
            raise DataFormatError("no @relation: this is not an ARFF file", source=self.source)
        if not self.header.attributes:
            raise DataFormatError("no attributes and no @data section", source=self.source)
        raise DataFormatError("no @data section after the attributes", source=self.source)

    def _line(self, line: str, number: int) -> None:
        header = self.header
        tokens = tokenize(line)
        if not tokens:
            return
        kind, text = tokens[0]
        keyword = text.lower() if kind == WORD else ""
        if keyword == "@relation":
            if header.relation is not None:
                raise LineError("a second @relation")
            header.relation = _relation_name(tokens)
            header.relation_line = number
        elif keyword in ("@attribute", "@data", "@end") and header.relation is None:
            raise LineError(
                f"no @relation before {text}: an ARFF file starts with '@relation <name>'"
            )
        elif keyword == "@attribute":
            attribute = _attribute(tokens)
            if attribute.name in self._names:
                raise LineError("duplicate attribute name", attribute.name)
            self._names.add(attribute.name)
            header.attributes.append(attribute)
        elif keyword == "@data":
            if len(tokens) > 1:
                raise LineError(f"unexpected {describe(tokens[1])} after @data")
            if not header.attributes:
                raise LineError("no attributes: @data comes before any @attribute")
            header.data_line = number
        elif keyword == "@end":
            raise LineError("@end outside a relational attribute")
        elif header.relation is None:
            raise LineError(
                f"no @relation: expected '@relation <name>', found {describe(tokens[0])}"
            )
        else:
            raise LineError(f"expected @attribute or @data, found {describe(tokens[0])}")


def _relation_name(tokens: list[Token]) -> str:
    if len(tokens) < 2 or tokens[1][0] not in (WORD, QUOTED):
        raise LineError("@relation needs a name")
    if len(tokens) > 2:
        raise LineError(
            f"unexpected {describe(tokens[2])} after the relation name "
            "(quote a name that contains spaces)"
        )
    return tokens[1][1]


def _attribute(tokens: list[Token]) -> Attribute:
    if len(tokens) < 2 or tokens[1][0] not in (WORD, QUOTED):
        raise LineError("@attribute needs a name and a type")
    name = tokens[1][1]
    if len(tokens) < 3:
        raise LineError("@attribute needs a type after the name", name)
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
            raise LineError(str(error), name) from None
        attribute = Attribute(name, "date", (), text, pattern)
    elif kind == WORD and text.lower() == "relational":
        raise LineError("relational attributes are not supported", name)
    else:
        raise LineError(
            f"unknown attribute type {describe(tokens[2])} (expected numeric, real, "
            "integer, string, date or a {list, of, nominal, values})",
            name,
        )
    if len(tokens) > end:
        raise LineError(f"unexpected {describe(tokens[end])} after the attribute type", name)
    return attribute


def _nominal_labels(tokens: list[Token], name: str) -> tuple[tuple[str, ...], int]:
    labels: list[str] = []
    seen: set[str] = set()
    for position in range(3, len(tokens)):
        kind, text = tokens[position]
        if kind == CLOSE:
            return tuple(labels), position + 1
        if kind == OPEN:
            raise LineError("'{' inside a list of nominal values", name)
        if text in seen:
            raise LineError(f"nominal value '{text}' is declared twice", name)
        seen.add(text)
        labels.append(text)
    raise LineError("the list of nominal values has no closing '}'", name)
