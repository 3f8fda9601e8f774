"""LineBlocks refuses a line longer than its limit exactly at the limit, wherever the line
sits and however the chunks of the stream fall: the service's early refusal of an upload
(app/api/multipart_lines.py) promises to refuse only what this reader refuses."""

from __future__ import annotations

import io

import pytest

from touchbench.benchmark.errors import DataFormatError
from touchbench.benchmark.io import textfile
from touchbench.benchmark.io.textfile import MAX_LINE_BYTES, LineBlocks

LIMIT = 100


def _read_all(data: bytes, *, block_bytes: int, header_lines: int) -> list[bytes]:
    """The lines as a reader takes them: ``header_lines`` one by one, then blocks."""
    lines = LineBlocks(io.BytesIO(data), "utf-8", block_bytes=block_bytes, source="f.arff")
    taken = []
    for _ in range(header_lines):
        line = lines.next_line()
        if line is None:
            return taken
        taken.append(line)
    for block, _ in lines.blocks():
        taken += block.splitlines()
    return taken


@pytest.mark.parametrize("block_bytes", [7, 64, 99, 100, 101, 150, 1000])
@pytest.mark.parametrize("header_lines", [0, 1, 3, 10])
@pytest.mark.parametrize("where", [0, 1, 4])
@pytest.mark.parametrize("end", [b"\n", b"\r\n", b"\r"])
def test_a_line_over_the_limit_is_refused_and_one_at_it_is_read(
    monkeypatch: pytest.MonkeyPatch, block_bytes: int, header_lines: int, where: int, end: bytes
) -> None:
    monkeypatch.setattr(textfile, "MAX_LINE_BYTES", LIMIT)
    short = [b"a,b,c"] * 6
    at_limit = [*short[:where], b"x" * LIMIT, *short[where:]]
    data = end.join(at_limit) + end
    assert _read_all(data, block_bytes=block_bytes, header_lines=header_lines) == at_limit
    over = [*short[:where], b"x" * (LIMIT + 1), *short[where:]]
    with pytest.raises(DataFormatError) as refused:
        _read_all(end.join(over) + end, block_bytes=block_bytes, header_lines=header_lines)
    assert str(refused.value).startswith(f"f.arff:{where + 1}: a line longer than 100 bytes")


def test_the_default_limit_holds_for_a_line_that_ends_in_the_chunk_past_it() -> None:
    """With the default chunks (4 MiB), a line of the limit and a half ends in the third
    chunk: it was read whole before, as were lines up to three chunks long."""
    line = b"1," * ((MAX_LINE_BYTES + MAX_LINE_BYTES // 2) // 2)
    data = b"@data\n" + line + b"\n1,2\n"
    with pytest.raises(DataFormatError, match=r"f\.arff:2: a line longer than 8,388,608 bytes"):
        _read_all(data, block_bytes=textfile.BLOCK_BYTES, header_lines=1)
    with pytest.raises(DataFormatError, match=r"f\.arff:2: a line longer than 8,388,608 bytes"):
        _read_all(data, block_bytes=textfile.BLOCK_BYTES, header_lines=2)
    fits = b"@data\n" + b"1" * MAX_LINE_BYTES + b"\n1,2\n"
    assert len(_read_all(fits, block_bytes=textfile.BLOCK_BYTES, header_lines=1)) == 3
