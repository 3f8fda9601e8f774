"""The fast ways of reading ARFF agree with WEKA's tokenizer, value for value, bit for bit.

``parser="tokenizer"`` reads every row with the exact tokenizer; ``"vectorised"`` hands
every plain block to Arrow's CSV reader (and the rest to the comma split or the tokenizer);
``"auto"`` is what users get.  Every ARFF text of the tests and of ``../shared/datasets``
must read the same three ways, or fail the same way at the same line.
"""

from __future__ import annotations

import math
import os
from decimal import Context, Decimal
from pathlib import Path

import numpy as np
import pytest

from tests.support.arff_texts import CANONICAL, HEADER, MESSY, random_dataset
from tests.support.synthetic import TOUCH_ARFF
from touchbench.benchmark.dataset import Dataset
from touchbench.benchmark.errors import DataFormatError
from touchbench.benchmark.io import arff_reader
from touchbench.benchmark.io.arff import dumps_arff, loads_arff, open_arff, read_arff

PARSERS = ("tokenizer", "vectorised", "auto")


def outcome(read: object) -> tuple[str, object]:
    """What reading gives: the data set's parts bit for bit, or the error's place and text."""
    try:
        dataset = read()  # type: ignore[operator]
    except DataFormatError as error:
        return ("error", (error.line, error.attribute, error.message))
    assert isinstance(dataset, Dataset)
    weights = None if dataset.weights is None else dataset.weights.tobytes()
    return (
        "data",
        (dataset.schema, dataset.values.shape, dataset.values.tobytes(), weights, dataset.sparse),
    )


def assert_all_parsers_agree(text: str | bytes) -> tuple[str, object]:
    results = [outcome(lambda p=p: loads_arff(text, parser=p)) for p in PARSERS]
    assert results[1] == results[0], f"vectorised differs from the tokenizer on {text!r:.300}"
    assert results[2] == results[0], f"auto differs from the tokenizer on {text!r:.300}"
    return results[0]


NOMINAL_HEADER = (
    "@relation t\n@attribute g {tap,slap,'0',1}\n@attribute x numeric\n@attribute y REAL\n@data\n"
)

PLAIN_CASES = {
    "quoted and bare labels": "'tap',1.5,2\nslap,-0,1e-300\n'0',?,?\n1,7,8\n",
    "quoted numbers": "tap,'1.5','2'\n",
    "numbers a C parser may refuse": "tap,nan,1_000\nslap,NaN,-inf\n",
    "not a number and infinities": "tap,nan,-nan\nslap,NaN,-inf\n0,Infinity,+inf\n",
    "spellings of numbers": "tap,+1,1.\ntap,.5,-0\ntap,1E+05,00012\ntap,0e0,-0.0\n",
    "almost numbers": "tap,1e,2\n",
    "hexadecimal": "tap,0x10,2\n",
    "other digits": "tap,\u0661\u0662,2\n",
    "numbers at the edges of float64": (
        "tap,4.9e-324,2.4703282292062327e-324\ntap,1.7976931348623157e308,1e309\n"
        "tap,2.2250738585072011e-308,9007199254740993\n"
        "tap,0.1000000000000000055511151231257827,123456789012345678901234567890\n"
    ),
    "blank lines and CRLF": "tap,1,2\r\n\r\nslap,3,4\r\n",
    "a lone carriage return": "tap,1,2\rslap,3,4\n",
    "last line without a break": "tap,1,2\nslap,3,4",
    "too few fields made up by too many": "tap,1\nslap,2,3,4\n",
    "too many fields on the first line": "tap,1,2,3\nslap,2,3\n",
    "too few fields": "tap,1,2\nslap,2\n",
    "empty field": "tap,,1,2\n",
    "leading comma": ",tap,1,2\n",
    "trailing comma": "tap,1,2,\n",
    "spaces": "tap, 1, 2\n",
    "tab": "tap,1\t,2\n",
    "quoted question mark": "'?',1,2\n",
    "unknown label": "tip,1,2\n",
    "quote inside a field": "ta'p',1,2\n",
    "text after a quote": "'ta'p,1,2\n",
    "quoted comma": "'tap,slap',1\n",
    "unterminated quote": "'tap,1,2\n",
    "quote pair across lines": "'tap,1,2\nslap',1,2\n",
    "comment": "tap,1,2 % note\n",
    "weight": "tap,1,2,{3}\n",
    "sparse": "{1 2}\n",
    "control character": "tap,1,2\x0b\n",
}


@pytest.mark.parametrize("case", sorted(PLAIN_CASES))
def test_plain_block_edge_cases_read_as_the_tokenizer_reads_them(case: str) -> None:
    assert_all_parsers_agree(NOMINAL_HEADER + PLAIN_CASES[case])


def test_the_fast_path_is_taken_and_refuses_what_it_cannot_prove() -> None:
    from touchbench.benchmark.io.arff_fast import plain_plan, read_plain_block

    plan = plain_plan(loads_arff(NOMINAL_HEADER).schema.attributes)
    assert plan is not None
    read = read_plain_block(b"'tap',1.5,?\n\nslap,2,3\n", plan, encoding="utf-8")
    assert read is not None
    values, rows = read
    np.testing.assert_array_equal(values, [[0, 1.5, np.nan], [1, 2, 3]])
    np.testing.assert_array_equal(rows, [0, 2])
    for refused in (b"tap,1_000,1\n", b"tap,1\nslap,2,3,4\n", b"tip,1,2\n", b"'tap,'1,2\n"):
        assert read_plain_block(refused, plan, encoding="utf-8") is None
    labels_with_spaces = loads_arff("@relation r\n@attribute g {'a b'}\n@data\n")
    assert plain_plan(labels_with_spaces.schema.attributes) is None


SPELLINGS = ["nan", "-nan", "NaN", "inf", "-Infinity", "+1", "1.", ".5", "-0", "+0", "1E+05",
             "00012", "0e0", "-0.0", "1e-400", "4.9e-324", "1.7976931348623159e308"]  # fmt: skip


def test_the_fast_path_reads_every_spelling_of_a_number_as_python_does() -> None:
    from touchbench.benchmark.io.arff_fast import plain_plan, read_plain_block

    plan = plain_plan(loads_arff(NOMINAL_HEADER).schema.attributes)
    assert plan is not None
    block = "".join(f"tap,{text},?\n" for text in SPELLINGS).encode()
    read = read_plain_block(block, plan, encoding="utf-8")
    assert read is not None, "the fast path refused numbers it should read"
    expected = np.array([float(text) for text in SPELLINGS])
    assert read[0][:, 1].tobytes() == expected.tobytes()
    assert read[0][:, 2].tobytes() == np.full(len(SPELLINGS), np.nan).tobytes()


@pytest.mark.parametrize("text", [CANONICAL, MESSY, TOUCH_ARFF, HEADER + "1,x\n?,y,{2}\n"])
def test_the_arff_texts_of_the_tests_read_alike(text: str) -> None:
    assert assert_all_parsers_agree(text)[0] == "data"


@pytest.mark.parametrize("seed", range(40))
def test_random_data_sets_read_alike(seed: int) -> None:
    text = dumps_arff(random_dataset(np.random.default_rng(seed)))
    assert assert_all_parsers_agree(text)[0] == "data"


_MUTATIONS = ["'", ",", " ", "?", "\r", "\n", ",,", "''", "1e5", "-", ".", "nan", "x", "é"]


@pytest.mark.parametrize("seed", range(60))
def test_mutated_plain_blocks_read_alike(seed: int) -> None:
    rng = np.random.default_rng(seed)
    labels = ["tap", "slap", "0", "1"]
    lines = []
    for _ in range(int(rng.integers(1, 12))):
        label = labels[int(rng.integers(len(labels)))]
        if rng.random() < 0.5:
            label = f"'{label}'"
        numbers = [repr(float(v)) for v in rng.normal(scale=10.0 ** rng.integers(-5, 5), size=2)]
        lines.append(",".join([label, *numbers]))
    body = "\n".join(lines) + "\n"
    for _ in range(int(rng.integers(0, 3))):
        at = int(rng.integers(len(body) + 1))
        body = body[:at] + _MUTATIONS[int(rng.integers(len(_MUTATIONS)))] + body[at:]
    assert_all_parsers_agree(NOMINAL_HEADER.replace("{tap,slap,'0',1}", "{tap,slap,0,1}") + body)


def test_every_float_text_reads_as_python_reads_it() -> None:
    rng = np.random.default_rng(7)
    bits = rng.integers(0, 2**63, size=3000, dtype=np.uint64)
    values = bits.view(np.float64)
    values = values[np.isfinite(values)]
    texts = [repr(float(v)) for v in values] + [f"{float(v):.12e}" for v in values[:500]]
    texts += [
        f"{rng.integers(0, 10**18)}.{rng.integers(0, 10**18)}e{rng.integers(-330, 310)}"
        for _ in range(500)
    ]
    # Exact midpoints between neighbouring doubles: rounding to even decides them.
    exact = Context(prec=1000)
    texts += [
        str(exact.add(Decimal(float(v)), exact.divide(Decimal(math.ulp(float(v))), 2)))
        for v in values[:300]
    ]
    body = "".join(f"tap,{text},{text}\n" for text in texts)
    from touchbench.benchmark.io.arff_fast import plain_plan, read_plain_block

    plan = plain_plan(loads_arff(NOMINAL_HEADER).schema.attributes)
    assert plan is not None
    read = read_plain_block(body.encode(), plan, encoding="utf-8")
    assert read is not None, "the fast path refused the block"
    expected = np.array([float(text) for text in texts])
    assert read[0][:, 1].tobytes() == expected.tobytes()
    assert assert_all_parsers_agree(NOMINAL_HEADER + body)[0] == "data"


def test_a_block_arrow_reads_in_several_batches_reads_alike() -> None:
    """Over a megabyte of rows (Arrow parses it in batches), missing values everywhere."""
    from touchbench.benchmark.io.arff_fast import plain_plan, read_plain_block

    rng = np.random.default_rng(3)
    labels = np.array(["tap", "'slap'", "0", "'1'", "?"])
    numbers = rng.normal(scale=1e3, size=(40_000, 2)).astype(str)
    numbers[rng.random(numbers.shape) < 0.1] = "?"
    picked = labels[rng.integers(0, labels.size, 40_000)]
    body = "".join(f"{g},{x},{y}\n" for g, (x, y) in zip(picked, numbers, strict=True))
    assert len(body) > 1 << 20
    plan = plain_plan(loads_arff(NOMINAL_HEADER).schema.attributes)
    assert plan is not None
    read = read_plain_block(body.encode(), plan, encoding="utf-8")
    assert read is not None, "the fast path refused the block"
    exact = loads_arff(NOMINAL_HEADER + body, parser="tokenizer")
    assert read[0].tobytes() == exact.values.tobytes()


def test_blocks_stream_the_file_with_line_numbers(tmp_path: Path) -> None:
    rows = [f"{'tap' if i % 3 else 'slap'},{i / 7!r},{i}" for i in range(3000)]
    rows[1500] = "% a comment in the middle"
    rows[2100] = "tap,1,2,{0.5}"
    path = tmp_path / "streamed.arff"
    path.write_text(NOMINAL_HEADER + "\n".join(rows) + "\n", encoding="utf-8")
    whole = read_arff(path, parser="tokenizer")
    for parser in PARSERS:
        with open_arff(path, parser=parser, block_bytes=4096) as reader:
            blocks = list(reader.blocks())
            schema = reader.schema
        assert len(blocks) > 10
        values = np.vstack([block.values for block in blocks])
        lines = np.concatenate([block.lines for block in blocks])  # type: ignore[misc]
        assert schema == whole.schema
        assert values.tobytes() == whole.values.tobytes()
        data_line = NOMINAL_HEADER.count("\n") + 1
        expected_lines = [data_line + i for i in range(3000) if i != 1500]
        assert lines.tolist() == expected_lines
        weighted = [block.weights for block in blocks if block.weights is not None]
        assert len(weighted) == 1 and 0.5 in weighted[0]


def test_an_error_in_a_late_block_names_its_line(tmp_path: Path) -> None:
    rows = ["tap,1,2"] * 5000
    rows[4321] = "tap,1,oops"
    path = tmp_path / "late.arff"
    path.write_text(NOMINAL_HEADER + "\n".join(rows) + "\n", encoding="utf-8")
    for parser in PARSERS:
        with (
            pytest.raises(DataFormatError, match="'oops' is not a number") as caught,
            open_arff(path, parser=parser, block_bytes=2048) as reader,
        ):
            list(reader.blocks())
        assert caught.value.line == NOMINAL_HEADER.count("\n") + 4322
        assert caught.value.attribute == "y"


@pytest.mark.parametrize("encoding", ["utf-8", "latin-1", "utf-16"])
def test_encodings_and_line_ends_stream_alike(tmp_path: Path, encoding: str) -> None:
    header = (
        "@relation caf\u00e9\r\n@attribute a {\u00e9t\u00e9,hiver}\r\n"
        "@attribute n numeric\r\n@data\r\n"
    )
    summer = "\u00e9t\u00e9"
    body = "".join(f"{summer if i % 2 else 'hiver'},{i}\r\n" for i in range(2000))
    path = tmp_path / "encoded.arff"
    path.write_bytes((header + body).encode(encoding))
    expected = loads_arff((header + body).replace("\r\n", "\n"), parser="tokenizer")
    for parser in PARSERS:
        with open_arff(path, parser=parser, block_bytes=1000) as reader:
            assert reader.scan.encoding == encoding
            read = reader.read()
        assert read.values.tobytes() == expected.values.tobytes()
        assert read.schema == expected.schema


def test_a_latin1_byte_late_in_the_file_decodes_the_whole_file_as_latin1(tmp_path: Path) -> None:
    header = "@relation r\n@attribute a {\u00e9t\u00e9,hiver}\n@data\n".encode()
    path = tmp_path / "mixed.arff"
    path.write_bytes(header + "\u00e9t\u00e9\n".encode() * 3000 + b"% caf\xe9\n")
    expected = loads_arff(path.read_bytes(), parser="tokenizer")
    assert expected.schema.attributes[0].values[0] == "\u00e9t\u00e9".encode().decode("latin-1")
    with open_arff(path, block_bytes=512) as reader:
        assert reader.scan.encoding == "latin-1"
        assert reader.read().equals(expected)


def test_devices_pipes_and_binary_files_are_refused_before_they_are_read(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    with pytest.raises(DataFormatError, match="not a regular file"):
        read_arff("/dev/zero")
    fifo = tmp_path / "pipe.arff"
    os.mkfifo(fifo)
    with pytest.raises(DataFormatError, match="not a regular file"):
        read_arff(fifo)

    def no_scan(*args: object, **kwargs: object) -> None:
        raise AssertionError("the whole file was read")

    monkeypatch.setattr(arff_reader, "scan_file", no_scan)
    wav = tmp_path / "touch.arff"
    wav.write_bytes(b"RIFF\x24\x08\x00\x00WAVEfmt " + bytes(1 << 20))
    with pytest.raises(DataFormatError, match="not a text file"):
        read_arff(wav)
    log = tmp_path / "log.arff"
    log.write_text("2024-01-01 started\n" * 500_000, encoding="utf-8")  # over 8 MB
    with pytest.raises(DataFormatError, match="no @relation") as caught:
        read_arff(log)
    assert caught.value.line == 1


def test_values_that_read_as_infinite_are_kept_for_the_caller_to_judge() -> None:
    dataset = loads_arff(NOMINAL_HEADER + "tap,1e309,-Infinity\n", parser="vectorised")
    assert math.isinf(dataset.values[0, 1]) and math.isinf(dataset.values[0, 2])


REFERENCE_FILES = (
    "uc3m-touch/mini/gesture_and_place.arff",
    "uc3m-touch/maggie/gesture_and_place.arff",
    "uc3m-touch/mini/weka_results_gesture.arff",
    "uc3m-touch/mini/weka_results_place.arff",
    "uc3m-touch/maggie/weka_results_gesture.arff",
    "uc3m-touch/maggie/weka_results_place.arff",
)


@pytest.mark.shared
@pytest.mark.parametrize("relative", REFERENCE_FILES)
def test_every_reference_file_reads_alike(shared_datasets: Path, relative: str) -> None:
    path = shared_datasets / relative
    results = [outcome(lambda p=p: read_arff(path, parser=p)) for p in PARSERS]
    assert results[1] == results[0] and results[2] == results[0]


@pytest.mark.shared
def test_the_reference_files_are_all_compared(shared_datasets: Path) -> None:
    found = {str(p.relative_to(shared_datasets)) for p in shared_datasets.rglob("*.arff")}
    assert found == set(REFERENCE_FILES)
