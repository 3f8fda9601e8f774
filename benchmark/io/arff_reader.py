"""Reading WEKA ARFF files: whole into a :class:`~benchmark.dataset.Dataset`, or streamed.

:class:`ArffReader` reads the header when it is made and then hands the data section on in
blocks of instances, so that a file of any size is read with memory bounded by the block
size.  Each block of lines is read the fastest way that is exact for it:

1. plain blocks (numbers and nominal labels between single commas) by Arrow's CSV reader
   (:mod:`benchmark.io.arff_fast`);
2. other lines without double quotes, backslashes, braces or comments by splitting on
   commas, a column at a time (:mod:`benchmark.io.arff_data`);
3. everything else (sparse rows, weights, escapes, comments) by WEKA's tokenizer
   (:mod:`benchmark.io.tokens`), which also locates every error by line and attribute.

Columns set aside (:mod:`benchmark.io.columns`: the group column, ignored columns) are
read like the others and then taken out of each block.

All three give the same values, bit for bit: ``parser="tokenizer"`` reads every row the
third way, the reference the others are tested against.  Arrow reads plain blocks in
threads, a few blocks ahead of the one handed on (:mod:`benchmark.io.read_ahead`); the
other ways read in order, in the thread that iterates :meth:`ArffReader.blocks`.
"""

from __future__ import annotations

import hashlib
import io
import os
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import BinaryIO, Literal

import numpy as np

from touchbench.benchmark.dataset import (
    Attribute,
    Dataset,
    InstanceBlock,
    Schema,
    join_blocks,
    meka_target_count,
    resolve_targets,
)
from touchbench.benchmark.errors import ConfigurationError, DataFormatError
from touchbench.benchmark.io.arff_data import DataSection
from touchbench.benchmark.io.arff_fast import plain_plan, read_plain_block
from touchbench.benchmark.io.arff_header import Header, HeaderParser
from touchbench.benchmark.io.columns import ColumnChoice, plan_columns
from touchbench.benchmark.io.read_ahead import ordered_ahead
from touchbench.benchmark.io.textfile import (
    BLOCK_BYTES,
    SNIFF_BYTES,
    FileScan,
    LineBlocks,
    Progress,
    check_regular_file,
    decode_text,
    open_binary,
    scan_file,
    sniff_text,
    split_lines,
)

TargetSpec = int | Sequence[str] | None
Parser = Literal["auto", "vectorised", "tokenizer"]
#: Blocks smaller than this are split on commas rather than handed to Arrow, whose import
#: costs more than it saves on a small file.
VECTORISED_MIN_BYTES = 1 << 20
#: Files larger than this have their first bytes parsed as a header before they are read
#: whole (a smaller file is read so fast that the reader may as well say what is wrong).
EARLY_CHECK_BYTES = 8 << 20


class ArffReader:
    """An ARFF text whose header is read; its instances come block by block.

    Parameters
    ----------
    stream : binary stream
        The file, positioned at its start.
    scan : FileScan
        Size, digest and encoding of the whole stream (:func:`scan_file`).
    source : str
        The file name, for error messages.
    targets : int, sequence of str, or None
        ``None``: MEKA's ``-C`` in the relation name, else the last attribute; ``N``:
        the first N attributes; ``-N``: the last N; names: those attributes.
    parser : {"auto", "vectorised", "tokenizer"}
        ``auto`` hands plain blocks of at least :data:`VECTORISED_MIN_BYTES` to Arrow;
        ``vectorised`` hands it every plain block; ``tokenizer`` reads every row with
        WEKA's tokenizer.
    block_bytes : int
        About how many bytes of the file each block of instances comes from.
    errors : str
        How undecodable bytes are handled (``"surrogatepass"`` for text given as str).
    columns : ColumnChoice, optional
        The attribute naming each instance's group and the attributes left out; the
        targets are chosen among all the file's attributes, and may be neither.

    Raises
    ------
    DataFormatError
        If the header is wrong or the targets do not exist.
    ColumnError
        A column choice that does not fit the file (see :func:`plan_columns`).
    """

    def __init__(
        self,
        stream: BinaryIO,
        scan: FileScan,
        *,
        source: str,
        targets: TargetSpec = None,
        parser: Parser = "auto",
        block_bytes: int = BLOCK_BYTES,
        errors: str = "strict",
        columns: ColumnChoice | None = None,
    ) -> None:
        self.scan = scan
        self.source = source
        self.parser = parser
        self._lines = LineBlocks(
            stream, scan.encoding, block_bytes=block_bytes, errors=errors, source=source
        )
        self.header = self._read_header()
        assert self.header.relation is not None
        names = [attribute.name for attribute in self.header.attributes]
        try:
            self.target_indices = resolve_targets(targets, names, relation=self.header.relation)
        except ConfigurationError as error:
            line = self.header.relation_line if targets is None else None
            raise DataFormatError(f"targets: {error}", source=source, line=line) from None
        self.columns = plan_columns(
            names,
            self.target_indices,
            columns,
            source=source,
            targets_by=None if targets is not None else _targets_by(self.header.relation),
        )
        self._data = DataSection(self.header.attributes, source)
        self._plan = plain_plan(self.header.attributes) if parser != "tokenizer" else None
        self._finished = False

    @property
    def schema(self) -> Schema:
        """The data set's schema (without the columns set aside); string tables are
        complete once :meth:`blocks` is exhausted."""
        assert self.header.relation is not None
        attributes = self._data.finish() if self._finished else self._data.attributes()
        return self.columns.schema(self.header.relation, attributes)

    @property
    def sparse(self) -> bool:
        """Whether some row read so far was sparse."""
        return self._data.sparse

    @property
    def bytes_read(self) -> int:
        """Bytes of the file read so far (for progress)."""
        return self._lines.bytes_read

    def blocks(self) -> Iterator[InstanceBlock]:
        """The instances, in blocks of the file's order.

        Yields
        ------
        InstanceBlock
            ``values`` of shape (n, n_attributes) (the data set's attributes: the columns
            set aside taken out), ``weights`` (``None`` unless a row of the block has
            one), ``groups`` (the group column's values as text, if there is one) and
            ``lines``, the line each instance was read from.

        Raises
        ------
        DataFormatError
            At the first wrong line, naming it and the attribute.
        """
        for (block, first_line), parsed in ordered_ahead(
            self._lines.blocks(), self._read_plain, self._is_for_arrow
        ):
            read = self._read_block(block, first_line, None if parsed is None else parsed.result())
            yield self.columns.block(read, self._group_attribute(), source=self.source)
        self._finished = True

    def _group_attribute(self) -> Attribute | None:
        """The group column's attribute as read so far (a string table grows as rows come)."""
        group = self.columns.group
        return None if group is None else self._data.columns[group].attribute()

    def read(self) -> Dataset:
        """The whole data set (reads the blocks that are left)."""
        blocks = list(self.blocks())
        return join_blocks(self.schema, blocks, sparse=self.sparse)

    def _read_header(self) -> Header:
        parser = HeaderParser(self.source)
        while (line := self._lines.next_line()) is not None:
            try:
                text = self._lines.decode(line)
            except UnicodeDecodeError:
                raise DataFormatError(
                    "not a text file (invalid encoding)", source=self.source
                ) from None
            if parser.feed(text, self._lines.lines_read):
                break
        return parser.finish()

    def _is_for_arrow(self, numbered: tuple[bytes, int]) -> bool:
        """Whether a block (with its first line's number) is one Arrow reads if plain."""
        return self._plan is not None and (
            self.parser == "vectorised" or len(numbered[0]) >= VECTORISED_MIN_BYTES
        )

    def _read_plain(self, numbered: tuple[bytes, int]) -> tuple[np.ndarray, np.ndarray] | None:
        """:func:`read_plain_block` of a block, in one of the threads that read ahead (so
        Arrow's own threads are not wanted: blocks are already read side by side)."""
        assert self._plan is not None
        return read_plain_block(
            numbered[0], self._plan, encoding=self._lines.encoding, threads=False
        )

    def _read_block(
        self, block: bytes, first_line: int, plain: tuple[np.ndarray, np.ndarray] | None
    ) -> InstanceBlock:
        """The instances of a block: ``plain`` if Arrow read it, else read line by line."""
        if plain is not None:
            values, rows = plain
            return InstanceBlock(values, lines=first_line + rows)
        lines = split_lines(self._lines.decode(block))
        if lines and lines[-1] == "" and block.endswith((b"\n", b"\r")):
            lines.pop()  # the line break that ends the block starts no line of its own
        return self._data.read(lines, first_line, split=self.parser != "tokenizer")


@contextmanager
def open_arff(
    path: str | os.PathLike[str],
    *,
    targets: TargetSpec = None,
    parser: Parser = "auto",
    block_bytes: int = BLOCK_BYTES,
    progress: Progress | None = None,
    source: str | None = None,
    columns: ColumnChoice | None = None,
) -> Iterator[ArffReader]:
    """An ARFF file opened for reading in blocks.

    The file must be a regular file whose first bytes are text and whose header is
    valid; it is then read once whole (:func:`scan_file`: digest and encoding, with
    ``progress``) before the reader is made.

    Parameters
    ----------
    path : str or path-like
        The file.
    targets, parser, block_bytes, columns
        As in :class:`ArffReader`.
    progress : callable, optional
        Called with (bytes read, file size) while the file is scanned.
    source : str, optional
        The name messages give the file (an upload's name when ``path`` is a temporary
        copy); ``path`` by default.

    Yields
    ------
    ArffReader

    Raises
    ------
    DataFormatError
        If the file does not exist, is not a regular file, is not text, or its header
        is wrong.
    """
    named = check_regular_file(path)
    source = source or named
    with open_binary(named) as stream:
        try:
            size = os.fstat(stream.fileno()).st_size
            head = stream.read(SNIFF_BYTES)
            sniff_text(head, source=source)
            if size > EARLY_CHECK_BYTES:
                _check_header_start(head, source)
            stream.seek(0)
            scan = scan_file(stream, source=source, size=size, progress=progress)
            stream.seek(0)
        except OSError as error:
            raise DataFormatError(
                f"cannot read the file: {error.strerror}", source=source
            ) from None
        yield ArffReader(
            stream,
            scan,
            source=source,
            targets=targets,
            parser=parser,
            block_bytes=block_bytes,
            columns=columns,
        )


def _targets_by(relation: str) -> str:
    """How the targets of a file whose user named none were chosen, for messages."""
    try:
        count = meka_target_count(relation)
    except ConfigurationError:
        count = None  # refused already when the targets were resolved
    if count is None:
        return "the last attribute, by default"
    return f"MEKA's -C {count} in the @relation"


def _check_header_start(head: bytes, source: str) -> None:
    """Refuse a file whose first bytes already show a wrong header, before reading it all."""
    parser = HeaderParser(source)
    utf16 = head.startswith((b"\xff\xfe", b"\xfe\xff"))
    text = head.decode("utf-16" if utf16 else "utf-8", "replace")
    lines = split_lines(text.removeprefix("\ufeff"))
    for number, line in enumerate(lines[:-1], start=1):  # the last line may be cut
        if parser.feed(line, number):
            return


def loads_arff(
    text: str | bytes,
    *,
    source: str = "<string>",
    targets: TargetSpec = None,
    parser: Parser = "auto",
    columns: ColumnChoice | None = None,
) -> Dataset:
    """Parse ARFF text.

    Parameters
    ----------
    text : str or bytes
        The whole file; bytes are decoded as UTF-16 after its byte-order mark, else as
        UTF-8 when they are valid UTF-8, else as Latin-1.
    source : str
        Name used in error messages.
    targets : int, sequence of str, or None
        ``None``: MEKA's ``-C`` in the relation name, else the last attribute; ``N``:
        the first N attributes; ``-N``: the last N; names: those attributes.
    parser : {"auto", "vectorised", "tokenizer"}
        As in :class:`ArffReader`.
    columns : ColumnChoice, optional
        As in :class:`ArffReader`.

    Returns
    -------
    Dataset
        ``values`` has shape (n_instances, n_attributes); ``weights`` is ``None`` unless
        some row has an instance weight; ``groups`` is ``None`` unless ``columns`` names
        a group column; ``sparse`` tells whether rows were sparse.

    Raises
    ------
    DataFormatError
        For anything wrong with the text, or targets that do not exist; the error
        carries the source, the 1-based line and the attribute where they apply.
    """
    data = decode_text(text, source=source).encode("utf-8", "surrogatepass")
    scan = FileScan(size=len(data), sha256=hashlib.sha256(data).hexdigest(), encoding="utf-8")
    reader = ArffReader(
        io.BytesIO(data),
        scan,
        source=source,
        targets=targets,
        parser=parser,
        errors="surrogatepass",
        columns=columns,
    )
    return reader.read()


def read_arff(
    path: str | os.PathLike[str],
    *,
    targets: TargetSpec = None,
    parser: Parser = "auto",
    source: str | None = None,
    columns: ColumnChoice | None = None,
) -> Dataset:
    """Read an ARFF file.

    Parameters
    ----------
    path : str or path-like
        The file.
    targets : int, sequence of str, or None
        As in :func:`loads_arff`.
    parser : {"auto", "vectorised", "tokenizer"}
        As in :class:`ArffReader`.
    source : str, optional
        The name messages give the file (an upload's name when ``path`` is a temporary
        copy); ``path`` by default.
    columns : ColumnChoice, optional
        As in :class:`ArffReader`.

    Returns
    -------
    Dataset
        See :func:`loads_arff`.

    Raises
    ------
    DataFormatError
        If the file does not exist, cannot be read, or is not valid ARFF.
    """
    with open_arff(path, targets=targets, parser=parser, source=source, columns=columns) as reader:
        return reader.read()
