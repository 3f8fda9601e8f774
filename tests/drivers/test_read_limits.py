"""drivers.limits: a CSV recording's work follows its size, whatever its values say."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest

from touchbench.drivers.csv_series import read_csv_series
from touchbench.drivers.errors import DriverError
from touchbench.drivers.files import read_recording
from touchbench.drivers.limits import LineTooLongError, ReadLimits, bounded_lines
from touchbench.drivers.resample import check_grid


def test_bounded_lines_refuse_a_long_line_without_reading_it_whole() -> None:
    handle = io.StringIO("a,b\n" + "x" * 50 + "\n" + "y" * 10_000)
    lines = bounded_lines(handle, limit=60, source="f.csv")
    assert next(lines) == "a,b\n" and next(lines) == "x" * 50 + "\n"
    with pytest.raises(LineTooLongError, match=r"^f\.csv:3: a line longer than 60 characters"):
        next(lines)
    assert handle.tell() == 4 + 51 + 62  # up to the limit and a line break, no further


def test_a_line_of_exactly_the_limit_is_read_whole_with_its_line_break() -> None:
    text = "x" * 8 + "\r\n" + "y" * 8 + "\n" + "z" * 9 + "\r\n"
    lines = bounded_lines(io.StringIO(text), limit=8, source="f")
    assert [next(lines), next(lines)] == ["x" * 8 + "\r\n", "y" * 8 + "\n"]
    with pytest.raises(LineTooLongError, match=r"^f:3: ") as refused:
        next(lines)
    assert refused.value.line == 3  # the file's own third line, not one more
    handle = io.TextIOWrapper(io.BytesIO(text.encode()), newline="", encoding="utf-8")
    assert [len(line) for line in bounded_lines(handle, limit=9, source="f")] == [10, 9, 11]


def test_a_gap_is_refused_before_the_grid_is_made() -> None:
    times = np.array([0.0, 0.01, 0.02, 50.0, 50.01])
    with pytest.raises(DriverError) as refused:
        check_grid(
            times,
            100.0,
            3,
            ReadLimits(gap_samples=1000, settings={"gap_samples": "SETTING"}),
            at=lambda i: f"f.csv:{i + 2}: column 't' jumps",
            before="the line before",
        )
    assert str(refused.value) == (
        "f.csv:5: column 't' jumps 49.98 s over the line before: resampling at 100 Hz would "
        "fill that gap with 4,998 samples, more than the 1,000 allowed (the setting SETTING "
        "raises the limit); split the recording at the gap"
    )
    check_grid(times, 100.0, 3, ReadLimits(gap_samples=5000), at=str, before="")
    with pytest.raises(DriverError, match=r"would make 5,002 samples x 3 channel\(s\) of 5"):
        check_grid(times, 100.0, 3, ReadLimits(cells=15_000), at=str, before="")


@pytest.mark.parametrize(
    ("stamp", "said"),
    [("nan", "nan is not a time"), ("inf", "inf is not a time"), ("-inf", "-inf is not")],
)
def test_non_finite_stamps_are_refused_with_their_line(
    tmp_path: Path, stamp: str, said: str
) -> None:
    path = tmp_path / "t.csv"
    path.write_text(f"time,a\n0,1\n0.01,2\n{stamp},3\n0.03,4\n", encoding="utf-8")
    with pytest.raises(DriverError, match=rf"t\.csv:4: column 'time': {said}"):
        read_recording(path)


def test_the_values_read_are_bounded(tmp_path: Path) -> None:
    path = tmp_path / "wide.csv"
    path.write_text("\n".join(",".join(["1"] * 10) for _ in range(20)) + "\n", encoding="utf-8")
    with pytest.raises(DriverError, match=r"wide\.csv:11: 11 samples x 10 channel\(s\)"):
        read_recording(path, samplerate=10.0, limits=ReadLimits(cells=100))
    assert read_recording(path, samplerate=10.0, limits=ReadLimits(cells=200)).n_channels == 10


def test_lines_are_named_across_blank_lines_quoted_lines_and_repeats(tmp_path: Path) -> None:
    """Each row's line is told after blank lines, a quoted field over two lines and a row
    logged twice (the line numbers are kept as runs, not one per row)."""
    path = tmp_path / "t.csv"
    path.write_text(
        'time,x,"y"\n'  # line 1
        "0.00,1,0\n"
        "\n"
        "0.01,2,0\n"  # line 4
        '0.02,3,"0\n"\n'  # lines 5 and 6: a quoted field over two lines
        "0.03,4,0\n"  # line 7
        "0.03,4,0\n"  # line 8: logged twice, left out
        "\n\n"
        "0.02,5,0\n"  # line 11: backwards
    )
    with pytest.raises(DriverError, match=r"^.*t\.csv:11: column 'time': the time does not rise"):
        read_csv_series(path, channels=["x"])
