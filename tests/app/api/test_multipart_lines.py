"""A form's text files followed line by line as the body streams in
(app.api.multipart_lines): a line over its reader's limit is refused at the chunk that
passes it, naming the line the reader would name, however the body is cut into chunks;
recordings and text the readers would not take as such are left to them."""

from __future__ import annotations

import io
import random
import re
from typing import Literal

import httpx
import pytest

from touchbench.app.api.multipart_lines import (
    READ_AHEAD,
    FilePart,
    LineRule,
    LongLine,
    MultipartLines,
    boundary_of,
)
from touchbench.drivers.limits import LineTooLongError, bounded_lines

CHUNK = 64 << 10


def _form(
    files: list[tuple[str, tuple[str, bytes]]], data: dict[str, str] | None = None
) -> tuple[bytes, bytes]:
    """The boundary and body httpx (the project's client) sends for a form."""
    request = httpx.Request("POST", "http://service/", files=files, data=data)
    boundary = boundary_of(request.headers["content-type"].encode())
    assert boundary is not None
    return boundary, request.read()


def _scanner(
    boundary: bytes,
    limit: int,
    *,
    breaks: Literal["any", "lf"] = "any",
    utf8: bool = False,
) -> MultipartLines:
    """A scanner whose ``.csv`` and ``.txt`` files have lines of at most ``limit``."""

    def choose(part: FilePart) -> LineRule | None:
        name = part.filename or "?"
        if not name.endswith((".csv", ".txt")):
            return None
        return LineRule(
            limit, lambda line: LineTooLongError(name, line, limit), breaks=breaks, utf8=utf8
        )

    return MultipartLines(boundary, choose)


def _fed(scanner: MultipartLines, body: bytes, cuts: list[int]) -> LongLine | None:
    """Feed ``body`` cut at ``cuts``; the line refused, if any (nothing fed after it)."""
    start = 0
    for end in [*cuts, len(body)]:
        found = scanner.feed(body[start:end])
        if found is not None:
            return found
        start = end
    return None


def _in_chunks(body: bytes, size: int) -> list[int]:
    return list(range(size, len(body), size))


def test_a_line_over_the_limit_is_refused_at_the_chunk_that_passes_it() -> None:
    limit = 1 << 20
    boundary, body = _form([("file", ("one-line.csv", b"0.5," * (5 << 20)))])
    scanner = _scanner(boundary, limit)
    found = _fed(scanner, body, _in_chunks(body, CHUNK))
    assert found is not None and found.line == 1
    assert str(found.error).startswith("one-line.csv:1: a line longer than 1,048,576 characters")
    # the bytes fed before the refusal: the limit, the part's headers, and one chunk
    assert scanner.consumed == found.consumed <= limit + CHUNK + 500
    assert scanner.consumed > limit

    # a strict UTF-8 reader decodes a little past the limit before it refuses: so does this
    for size in (CHUNK, 4096):
        scanner = _scanner(boundary, limit, utf8=True)
        found = _fed(scanner, body, _in_chunks(body, size))
        assert found is not None and found.line == 1
        assert limit + READ_AHEAD < scanner.consumed <= limit + READ_AHEAD + size + 500


@pytest.mark.parametrize("cut", range(-3, 50))
def test_a_delimiter_split_between_chunks_is_found(cut: int) -> None:
    """Every cut around the delimiter between a form field, a short CSV file and a long
    one: the long one is refused, named, and the field is read."""
    first = b"a,b\r\n1,2\r\n"
    boundary, body = _form(
        [("recordings", ("short.csv", first)), ("recordings", ("long.csv", b"x" * 300))],
        data={"format": "csv"},
    )
    at = body.index(b"--" + boundary, body.index(first)) - 2  # the "\r\n--boundary"
    scanner = MultipartLines(
        boundary,
        lambda part: LineRule(
            100, lambda line: LineTooLongError(f"{part.filename}#{part.index}", line, 100)
        ),
    )
    found = _fed(scanner, body, [at + cut])
    assert found is not None and str(found.error).startswith("long.csv#1:1: a line longer")
    assert found.part == FilePart("recordings", "long.csv", 1, {"format": "csv"})


@pytest.mark.parametrize("size", [1, 2, 3, 7, 100, CHUNK])
def test_a_line_break_split_between_chunks_is_one_line_break(size: int) -> None:
    """CRLF lines of exactly the limit, cut anywhere (between "\\r" and "\\n" too), pass;
    the longer line after them is named by its own number."""
    limit = 20
    text = (b"x" * limit + b"\r\n") * 5 + b"y" * limit + b"\r" + b"z" * (limit + 1) + b"\r\n"
    boundary, body = _form([("file", ("take.csv", text))])
    found = _fed(_scanner(boundary, limit), body, _in_chunks(body, size))
    assert found is not None and found.line == 7  # a lone "\r" ends line 6
    # the recording reader counts the same lines (drivers.limits.bounded_lines)
    handle = io.TextIOWrapper(io.BytesIO(text), newline="", encoding="utf-8")
    with pytest.raises(LineTooLongError) as refused:
        list(bounded_lines(handle, limit=limit, source="take.csv"))
    assert refused.value.line == 7


def test_a_binary_part_is_never_line_checked() -> None:
    wav = b"RIFF" + bytes(random.Random(3).getrandbits(8) for _ in range(4096)).replace(
        b"\n", b"-"
    ).replace(b"\r", b"-") * (3 * 256)
    assert len(wav) > 3 << 20 and b"\n" not in wav
    boundary, body = _form([("file", ("take.wav", wav)), ("other", ("notes.csv", b"a\n"))])
    assert _fed(_scanner(boundary, 1000), body, _in_chunks(body, CHUNK)) is None
    # nor is a text file holding NUL bytes (its reader says it is not text)
    boundary, body = _form([("file", ("zeros.csv", bytes(3 << 20)))])
    assert _fed(_scanner(boundary, 1000), body, _in_chunks(body, CHUNK)) is None


def test_the_second_of_two_text_files_is_named() -> None:
    boundary, body = _form(
        [
            ("recordings", ("first.csv", b"t,a\n" + b"0.1,2\n" * 5000)),
            ("recordings", ("second.txt", b"t,a\n0.1,2\n" + b"9" * 5000)),
        ]
    )
    found = _fed(_scanner(boundary, 4096), body, _in_chunks(body, 1000))
    assert found is not None
    assert str(found.error).startswith("second.txt:3: a line longer than 4,096 characters")
    assert (found.part.filename, found.part.index) == ("second.txt", 1)


def test_crlf_lines_just_under_the_limit_pass() -> None:
    limit = 1 << 20
    lines = b"".join(bytes([65 + i]) * (limit - i) + b"\r\n" for i in range(3))
    boundary, body = _form([("file", ("wide.csv", b"\xef\xbb\xbf" + lines))])  # BOM not counted
    for utf8 in (False, True):
        scanner = _scanner(boundary, limit, utf8=utf8)
        assert _fed(scanner, body, _in_chunks(body, CHUNK)) is None


def test_characters_are_counted_not_bytes_and_undecodable_text_is_left_to_its_reader() -> None:
    limit = 100
    boundary, body = _form([("file", ("accents.csv", "é".encode() * limit + b"\n"))])
    for size in (1, 3, 64):
        assert _fed(_scanner(boundary, limit), body, _in_chunks(body, size)) is None
    boundary, body = _form([("file", ("accents.csv", "é".encode() * (limit + 1) + b"\n"))])
    assert _fed(_scanner(boundary, limit), body, [len(body) // 2]) is not None
    # Latin-1 text: a strict UTF-8 reader fails on it first; a lenient one counts more
    boundary, body = _form([("file", ("latin.csv", "é".encode("latin-1") * 300 + b"\n"))])
    assert _fed(_scanner(boundary, limit, utf8=True), body, []) is None
    assert _fed(_scanner(boundary, limit), body, []) is not None
    # undecodable bytes within the strict reader's read-ahead past the limit: left to it
    tail = b"x" * (limit + 10) + b"\xff" + b"x" * (2 * READ_AHEAD)
    boundary, body = _form([("file", ("late.csv", tail))])
    assert _fed(_scanner(boundary, limit, utf8=True), body, _in_chunks(body, 16)) is None


def test_lines_end_at_line_feeds_alone_for_a_reader_that_says_so() -> None:
    limit = 50
    text = b"a,b\r\n" + b"1,2\r" * 20 + b"\n"  # 80 characters on line 2 for a "\n" reader
    boundary, body = _form([("file", ("mac.csv", text))])
    assert _fed(_scanner(boundary, limit), body, []) is None
    found = _fed(_scanner(boundary, limit, breaks="lf"), body, [])
    assert found is not None and found.line == 2


def test_only_the_first_lines_a_rule_names_are_checked() -> None:
    boundary, body = _form([("file", ("take.csv", b"t,a\n" + b"1" * 500 + b"\n"))])
    scanner = MultipartLines(
        boundary, lambda part: LineRule(100, lambda line: ValueError(line), lines=1)
    )
    assert _fed(scanner, body, [30]) is None


def _reference_line(text: bytes, limit: int) -> int | None:
    """The line the recording reader refuses (drivers.limits.bounded_lines), if any."""
    handle = io.TextIOWrapper(io.BytesIO(text), newline="", encoding="utf-8-sig")
    try:
        for _ in bounded_lines(handle, limit=limit, source="f"):
            pass
    except LineTooLongError as error:
        return error.line
    return None


def _reference_lf_line(text: bytes, limit: int) -> int | None:
    """The line a data set's CSV reader refuses (a run of ``limit + 1`` characters
    without ``\\n``: benchmark.io.csv.read_csv), if any."""
    decoded = text.decode("utf-8").removeprefix("\ufeff")
    found = re.search(rf"[^\n]{{{limit + 1}}}", decoded)
    return None if found is None else decoded.count("\n", 0, found.start()) + 1


@pytest.mark.parametrize("seed", range(40))
def test_the_line_refused_is_the_one_the_reader_refuses(seed: int) -> None:
    """Random texts of short and long lines, CRLF, CR and LF, accents and a BOM, cut into
    random chunks: the scanner refuses what the reader refuses, naming the same line."""
    rng = random.Random(seed)
    limit = rng.choice([5, 16, 40])
    pieces = [b"\xef\xbb\xbf"] if rng.random() < 0.3 else []
    for _ in range(rng.randint(1, 30)):
        width = rng.choice([0, 1, limit - 1, limit, limit, limit + 1, 2 * limit])
        pieces.append(
            "".join(rng.choice("ab,é1") for _ in range(width)).encode()
            + rng.choice([b"\n", b"\r\n", b"\r", b"\r\n"])
        )
    text = b"".join(pieces)
    boundary, body = _form([("file", ("f.csv", text))])
    cuts = sorted(rng.sample(range(1, len(body)), min(len(body) - 1, rng.randint(0, 40))))
    found = _fed(_scanner(boundary, limit, utf8=True), body, cuts)
    assert (found.line if found else None) == _reference_line(text, limit), text
    found = _fed(_scanner(boundary, limit, breaks="lf"), body, cuts)
    assert (found.line if found else None) == _reference_lf_line(text, limit), text


def test_only_multipart_form_data_has_a_boundary() -> None:
    assert boundary_of(b'multipart/form-data; boundary="a b"') == b"a b"
    assert boundary_of(b"multipart/form-data; boundary=xyz") == b"xyz"
    assert boundary_of(b"application/json") is None
    assert boundary_of(b"multipart/form-data") is None
