"""Opening a data file and reading it in blocks of whole lines, with memory bounded.

Only regular files are read: a device such as ``/dev/zero`` or a pipe may never end.  The
first bytes must look like text (no NUL bytes, few control characters), so that a WAV
recording or an archive is refused before it is read whole.

The encoding is decided for the whole file, as :func:`decode_text` decides it for text in
memory: UTF-16 when the file starts with its byte-order mark, else UTF-8 if the whole file
is valid UTF-8, else Latin-1.  :func:`scan_file` reads the file once to decide it,
computing the content digest on the way; :class:`LineBlocks` then reads it again as lines
(``\\r\\n``, ``\\r`` and ``\\n`` all end a line) and blocks of whole lines, in that encoding
(UTF-16 is handed on as UTF-8).
"""

from __future__ import annotations

import codecs
import hashlib
import os
import re
import stat
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import BinaryIO

import numpy as np

from touchbench.benchmark.errors import DataFormatError

#: Bytes looked at before anything else is read: they must look like text.
SNIFF_BYTES = 65536
#: Default size of the blocks of lines handed to the parsers.
BLOCK_BYTES = 4 << 20
#: The longest line :class:`LineBlocks` reads, in bytes: a file of one line (no line break)
#: would otherwise be held, and then split, whole.  Rows of sequence data sets are long
#: (44 channels x 800 steps are about 700 KB of text), hence the room.
MAX_LINE_BYTES = 8 << 20
#: The byte-order marks of UTF-16 (a file that starts with one is transcoded, not read as
#: bytes) and of UTF-8 (dropped).
UTF16_BOMS = (b"\xff\xfe", b"\xfe\xff")
UTF8_BOM = b"\xef\xbb\xbf"
_CONTROL = re.compile(r"[\x00-\x08\x0e-\x1f\x7f]")
_LINE_END = re.compile(rb"\r\n|\r|\n")

#: Called with (bytes read so far, file size) as a file is read.
Progress = Callable[[int, int], None]


@dataclass(frozen=True)
class FileScan:
    """What one reading of a whole file tells.

    Attributes
    ----------
    size : int
        Bytes in the file.
    sha256 : str
        Hex digest of the bytes, the key that recognises a file imported before.
    encoding : {"utf-8", "latin-1", "utf-16"}
        The encoding of the whole file.
    """

    size: int
    sha256: str
    encoding: str


def check_regular_file(path: str | os.PathLike[str]) -> str:
    """The file name as given, once it is known to be a regular file that can be read.

    Raises
    ------
    DataFormatError
        If there is no such file, or it is a folder, a device, a pipe or a socket.
    """
    source = os.fspath(path)
    try:
        mode = os.stat(source).st_mode
    except FileNotFoundError:
        raise DataFormatError("no such file", source=source) from None
    except OSError as error:
        raise DataFormatError(f"cannot read the file: {error.strerror}", source=source) from None
    if stat.S_ISDIR(mode):
        raise DataFormatError("is a directory, not a file", source=source)
    if not stat.S_ISREG(mode):
        raise DataFormatError(
            "not a regular file (a device, pipe or socket cannot be imported; copy the data "
            "to a file first)",
            source=source,
        )
    return source


def open_binary(source: str) -> BinaryIO:
    """``source`` opened for reading bytes, I/O problems as DataFormatError."""
    try:
        return open(source, "rb")
    except OSError as error:
        raise DataFormatError(f"cannot read the file: {error.strerror}", source=source) from None


def sniff_text(head: bytes, *, source: str) -> None:
    """Refuse a file whose first bytes are not text.

    Parameters
    ----------
    head : bytes
        The first :data:`SNIFF_BYTES` bytes (or fewer) of the file.
    source : str
        The file name, for error messages.

    Raises
    ------
    DataFormatError
        If the bytes hold a NUL (outside UTF-16) or more than 1 % control characters.
    """
    if head.startswith(UTF16_BOMS):
        text = head.decode("utf-16", errors="replace")
    else:
        if b"\x00" in head:
            raise DataFormatError("not a text file (it contains NUL bytes)", source=source)
        text = head.decode("utf-8", errors="replace")
    check_text_sample(text[:SNIFF_BYTES], source=source)


def check_text_sample(sample: str, *, source: str) -> None:
    """Raise DataFormatError if ``sample`` holds NUL or more than 1 % control characters."""
    if "\x00" in sample or len(_CONTROL.findall(sample)) > len(sample) // 100:
        raise DataFormatError("not a text file (it contains control characters)", source=source)


def scan_file(
    stream: BinaryIO,
    *,
    source: str,
    size: int | None = None,
    progress: Progress | None = None,
    chunk_bytes: int = 1 << 20,
) -> FileScan:
    """Read a whole binary stream once: its digest, its encoding, and whether it is text.

    Parameters
    ----------
    stream : binary stream
        Positioned at the start of the file; left at its end.
    source : str
        The file name, for error messages.
    size : int, optional
        The file's size, for ``progress``.
    progress : callable, optional
        Called with (bytes read, size) after each chunk.
    chunk_bytes : int
        Bytes read at a time.

    Returns
    -------
    FileScan

    Raises
    ------
    DataFormatError
        If the file is empty (or whitespace only), holds NUL bytes, or is invalid UTF-16.
    """
    digest = hashlib.sha256()
    total = 0
    utf16: codecs.IncrementalDecoder | None = None
    utf8: codecs.IncrementalDecoder | None = codecs.getincrementaldecoder("utf-8")()
    has_content = False
    while chunk := stream.read(chunk_bytes):
        digest.update(chunk)
        body = chunk
        if total == 0:
            if chunk.startswith(UTF16_BOMS):
                utf16 = codecs.getincrementaldecoder("utf-16")()
                utf8 = None
            body = chunk.removeprefix(UTF8_BOM)
        total += len(chunk)
        if utf16 is not None:
            try:
                text = utf16.decode(chunk)
            except UnicodeDecodeError:
                raise DataFormatError("not a text file (invalid UTF-16)", source=source) from None
            has_content = has_content or bool(text.removeprefix("\ufeff").strip())
        else:
            if b"\x00" in chunk:
                raise DataFormatError("not a text file (it contains NUL bytes)", source=source)
            has_content = has_content or bool(body.strip())
            if utf8 is not None and not chunk.isascii():
                try:
                    utf8.decode(chunk)
                except UnicodeDecodeError:
                    utf8 = None
        if progress is not None:
            progress(total, size or total)
    if utf16 is not None:
        try:
            utf16.decode(b"", final=True)
        except UnicodeDecodeError:
            raise DataFormatError("not a text file (invalid UTF-16)", source=source) from None
    elif utf8 is not None:
        try:
            utf8.decode(b"", final=True)
        except UnicodeDecodeError:
            utf8 = None
    if not has_content:
        raise DataFormatError("empty file", source=source)
    encoding = "utf-16" if utf16 is not None else "utf-8" if utf8 is not None else "latin-1"
    return FileScan(size=total, sha256=digest.hexdigest(), encoding=encoding)


def decode_text(data: str | bytes, *, source: str) -> str:
    """Decode a text file held in memory: UTF-8 (BOM ignored), UTF-16 with a BOM, else Latin-1.

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
        if data.startswith(UTF16_BOMS):
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
    check_text_sample(text[:SNIFF_BYTES], source=source)
    return text


def read_text_file(path: str | os.PathLike[str]) -> tuple[str, str]:
    """Read and decode a whole (regular, text) file, problems as DataFormatError.

    Returns
    -------
    text : str
        The decoded text (see :func:`decode_text`).
    source : str
        The file name as given, for error messages.
    """
    source = check_regular_file(path)
    with open_binary(source) as stream:
        sniff_text(stream.read(SNIFF_BYTES), source=source)
        stream.seek(0)
        try:
            data = stream.read()
        except OSError as error:
            raise DataFormatError(
                f"cannot read the file: {error.strerror}", source=source
            ) from None
    return decode_text(data, source=source), source


def split_lines(text: str) -> list[str]:
    """The lines of ``text``, with ``\\r\\n``, ``\\r`` and ``\\n`` all ending a line."""
    if "\r" in text:
        text = text.replace("\r\n", "\n").replace("\r", "\n")
    return text.split("\n")


def count_newlines(data: bytes) -> int:
    """How many ``\\n`` ``data`` holds (counted by NumPy: ``bytes.count`` is several times
    slower where they are dense, as in a block of short lines)."""
    return int(np.count_nonzero(np.frombuffer(data, dtype=np.uint8) == 10))


def count_line_ends(data: bytes) -> int:
    """How many lines ``data`` ends, ``\\r\\n``, ``\\r`` and ``\\n`` each ending one
    (``\\r\\n`` counts once)."""
    if b"\r" not in data:
        return count_newlines(data)
    codes = np.frombuffer(data, dtype=np.uint8)
    newlines, carriages = codes == 10, codes == 13
    pairs = int(np.count_nonzero(carriages[:-1] & newlines[1:]))
    return int(np.count_nonzero(newlines)) + int(np.count_nonzero(carriages)) - pairs


def long_line_error(source: str | None, line: int) -> DataFormatError:
    """The refusal of a line longer than :data:`MAX_LINE_BYTES` (as :class:`LineBlocks`
    finds it; the service's early refusal of an upload says the same)."""
    return DataFormatError(
        f"a line longer than {MAX_LINE_BYTES:,} bytes (a file of one line?)",
        source=source,
        line=line,
    )


class LineBlocks:
    """A binary stream read as lines, then as blocks of whole lines.

    Parameters
    ----------
    stream : binary stream
        Positioned at the start of the file.
    encoding : {"utf-8", "latin-1", "utf-16"}
        The file's encoding (:func:`scan_file`); UTF-16 is transcoded, so that
        :attr:`encoding` of what this object hands on is UTF-8.
    block_bytes : int
        About how many bytes each block holds (a block always ends with a whole line).
    errors : str
        How bytes that do not decode are handled by :meth:`decode` (``"strict"`` for
        files; text given as ``str`` comes as UTF-8 with ``"surrogatepass"``).
    source : str, optional
        The file's name, for the error of a line longer than :data:`MAX_LINE_BYTES`
        (refused as soon as that many bytes hold no line break).
    """

    def __init__(
        self,
        stream: BinaryIO,
        encoding: str,
        *,
        block_bytes: int = BLOCK_BYTES,
        errors: str = "strict",
        source: str | None = None,
    ) -> None:
        self._source = source
        self._stream = stream
        self._block_bytes = block_bytes
        self._utf16 = encoding == "utf-16"
        self._decoder = codecs.getincrementaldecoder("utf-16")() if self._utf16 else None
        self.encoding = "utf-8" if self._utf16 else encoding
        self.errors = errors
        self._buffer = b""
        self._position = 0
        self._eof = False
        self._started = False
        #: Lines handed out so far (the next line's number is this plus one).
        self.lines_read = 0
        #: Bytes of the underlying stream read so far.
        self.bytes_read = 0

    def decode(self, data: bytes) -> str:
        """Text of bytes this object handed out."""
        return data.decode(self.encoding, self.errors)

    def _read(self) -> bool:
        """Append the next chunk of the stream to the buffer; ``False`` at its end."""
        if self._eof:
            return False
        chunk = self._stream.read(self._block_bytes)
        self.bytes_read += len(chunk)
        if self._decoder is not None:
            text = self._decoder.decode(chunk, final=not chunk)
            data = (text if self._started else text.removeprefix("\ufeff")).encode(
                "utf-8", "surrogatepass"
            )
        else:
            data = chunk if self._started else chunk.removeprefix(UTF8_BOM)
        self._started = True
        self._eof = not chunk
        self._buffer = self._buffer[self._position :] + data
        self._position = 0
        return bool(chunk) or bool(data)

    def next_line(self) -> bytes | None:
        """The next line without its line break; ``None`` at the end of the stream."""
        while True:
            match = _LINE_END.search(self._buffer, self._position)
            # A "\r" ending the buffer may be the first half of a "\r\n" not read yet.
            if match is not None and (self._eof or match.end() < len(self._buffer)):
                # its end may have come in the same chunk that took it past the limit
                if match.start() - self._position > MAX_LINE_BYTES:
                    raise long_line_error(self._source, self.lines_read + 1)
                line = self._buffer[self._position : match.start()]
                self._position = match.end()
                self.lines_read += 1
                return line
            self._check_line(self._buffer, self._position)
            if self._read() or match is not None:
                continue  # read on; or the stream has ended, and that line end is whole
            if self._position >= len(self._buffer):
                return None
            line = self._buffer[self._position :]
            self._position = len(self._buffer)
            self.lines_read += 1
            return line

    def blocks(self) -> Iterator[tuple[bytes, int]]:
        """The rest of the stream as blocks of whole lines.

        Yields
        ------
        block : bytes
            Whole lines with their line breaks (the last block may end without one).
        first_line : int
            The 1-based line number of the block's first line.
        """
        while True:
            while len(self._buffer) - self._position < self._block_bytes and self._read():
                pass
            rest = self._buffer[self._position :]
            cut = self._cut(rest)
            while cut == 0 and rest:
                self._check_line(rest, 0)
                self._read()
                rest = self._buffer[self._position :]
                cut = self._cut(rest)
            if not rest:
                return
            block = rest[:cut]
            self._check_lines(block)
            self._buffer, self._position = rest[cut:], 0
            first_line = self.lines_read + 1
            self.lines_read += count_line_ends(block)
            yield block, first_line

    def _check_line(self, data: bytes, start: int) -> None:
        """Refuse the line from ``start`` when it is longer than :data:`MAX_LINE_BYTES`
        and has no line break yet (but perhaps the first byte of one, at the very end)."""
        if len(data) - start - data.endswith((b"\n", b"\r")) > MAX_LINE_BYTES:
            raise long_line_error(self._source, self.lines_read + 1)

    def _check_lines(self, block: bytes) -> None:
        """Refuse the first line of ``block`` longer than :data:`MAX_LINE_BYTES`: a line
        whose end came in the chunk that took it past the limit, or any line of a block
        larger than the limit."""
        if len(block) <= MAX_LINE_BYTES:
            return
        codes = np.frombuffer(block, dtype=np.uint8)
        breaks = np.flatnonzero((codes == 10) | (codes == 13))  # "\r\n": a line of 0
        starts = np.concatenate(([0], breaks + 1))
        lengths = np.concatenate((breaks, [len(block)])) - starts
        long = np.flatnonzero(lengths > MAX_LINE_BYTES)
        if long.size:
            before = block[: int(starts[long[0]])]
            raise long_line_error(self._source, self.lines_read + 1 + count_line_ends(before))

    def _cut(self, data: bytes) -> int:
        """Length of the longest prefix of whole lines (0 if there is none yet)."""
        if self._eof:
            return len(data)
        newline = data.rfind(b"\n")
        if newline >= 0:
            return newline + 1
        # Only "\r" line ends: one at the very end may be followed by "\n" in the next chunk.
        carriage = data.rfind(b"\r", 0, len(data) - 1)
        return carriage + 1
