"""Fold predictions (benchmark/predictions.py): a compact, versioned encoding without pickle,
and a finished run's predictions re-scored to its stored metrics exactly, for every kind
of problem (benchmark/evaluation/fold_scores.py)."""

from __future__ import annotations

import json
import math
import struct
import zlib

import numpy as np
import pytest

from touchbench.benchmark.errors import DataFormatError
from touchbench.benchmark.evaluation.fold_scores import score_fold
from touchbench.benchmark.predictions import VERSION, FoldPredictions, decode, encode
from touchbench.benchmark.problem import Problem
from touchbench.benchmark.results import TaskResult
from touchbench.benchmark.run.engine import run_tasks
from touchbench.benchmark.run.folds import make_folds

TIMEOUT = 600.0
#: Costs are measured, not scored: they are not re-scored.
COSTS = {"fit_time", "predict_time", "fit_cpu_time", "predict_cpu_time", "model_size"}


def _classes(n: int = 120, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    y = np.arange(n) % 3
    return rng.normal(size=(n, 4)) + 1.2 * y[:, None], y


def multiclass() -> Problem:
    X, y = _classes()
    return Problem(X=X, Y=y[:, None], n_classes=(3,), target_names=("gesture",))


def by_recording() -> Problem:
    """12 recordings of 10 windows, one class each."""
    rng = np.random.default_rng(1)
    y = np.repeat(np.arange(12) % 3, 10)
    groups = np.repeat([f"take{i:02d}.wav" for i in range(12)], 10).astype(object)
    X = rng.normal(size=(120, 3)) + y[:, None]
    return Problem(X=X, Y=y[:, None], n_classes=(3,), target_names=("g",), groups=groups)


def multitarget() -> Problem:
    rng = np.random.default_rng(2)
    Y = np.column_stack([np.arange(90) % 3, (np.arange(90) // 3) % 2])
    X = rng.normal(size=(90, 3)) + 2.0 * Y @ np.array([[1.0, 0, 0], [0, 0, 1.0]])
    return Problem(X=X, Y=Y, n_classes=(3, 2), target_names=("gesture", "place"))


def regression() -> Problem:
    rng = np.random.default_rng(3)
    X = rng.normal(size=(90, 3))
    Y = np.column_stack([X[:, 0] * 2 + rng.normal(size=90) * 0.1, X[:, 1] - X[:, 2]])
    return Problem(
        X=X, Y=Y, n_classes=(), target_names=("x", "y"), task="regression", coordinates=(0, 1)
    )


def _same(a: object, b: object) -> bool:
    """Equal, NaN equal to NaN, nested dicts and lists included."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, list | tuple) and isinstance(b, list | tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return a == b


CASES = [
    ("multi-class", multiclass, ["logistic", "svm-rbf", "voting", "voting-hard"], False),
    ("per recording", by_recording, ["nb", "ibk", "voting"], True),
    ("multi-target", multitarget, ["cr:nb", "cc:logistic", "lc:j48"], False),
    ("regression", regression, ["ridge", "knn5"], False),
]


@pytest.mark.parametrize(
    ("make", "classifiers", "recordings"),
    [case[1:] for case in CASES],
    ids=[case[0] for case in CASES],
)
def test_a_finished_run_re_scores_from_its_fold_predictions_exactly(
    make, classifiers, recordings
) -> None:
    problem = make()
    folds, _ = make_folds(
        problem.Y,
        n_folds=3,
        groups=problem.groups,
        regression=problem.kind == "regression",
    )
    results = run_tasks(
        problem, classifiers, folds, timeout=TIMEOUT, jobs=1, by_recording=recordings
    )
    assert results and all(r.ok for r in results), [r.error for r in results]
    assert {r.key.classifier for r in results} >= set(classifiers)
    for result in results:
        assert result.predictions is not None
        stored = TaskResult.from_json(json.loads(json.dumps(result.to_json())))
        blob = encode(result.predictions)
        again = score_fold(problem, decode(blob), by_recording=recordings)
        scores = {k: v for k, v in stored.metrics.items() if k not in COSTS}
        assert _same(again.metrics, scores), result.key
        assert _same(again.confusion, stored.confusion)
        assert _same(again.per_target, stored.per_target)
        assert _same(again.calibration, stored.calibration)


def test_the_encoding_gives_back_every_bit_and_keeps_codes_small() -> None:
    rng = np.random.default_rng(0)
    proba = rng.dirichlet(np.ones(4), size=50)
    proba[0] = [np.nextafter(0.25, 1), 0.25, 0.25, np.nextafter(0.25, 0)]
    original = FoldPredictions.of_classes(np.arange(100, 150), proba.argmax(axis=1), proba)
    blob = encode(original)
    back = decode(blob)
    assert back.same_as(original) and back.proba is not None and back.labels is not None
    assert back.probabilities.tobytes() == proba.tobytes()  # type: ignore[union-attr]
    assert back.indices.dtype == np.int64 and back.labels.dtype == np.int64
    length = struct.unpack_from("<I", blob, 4)[0]
    header = json.loads(blob[8 : 8 + length])
    assert blob[:4] == b"TBFP" and header["version"] == VERSION
    assert [(a["name"], a["dtype"]) for a in header["arrays"]] == [
        ("indices", "<i2"),  # rows up to 149: two bytes each
        ("labels", "<i1"),
        ("proba/0", "<f8"),
    ]
    several = FoldPredictions(
        np.arange(3),
        np.array([[0, 1], [2, 0], [1, 1]]),
        (np.eye(3), np.array([[0.2, 0.8], [1.0, 0.0], [0.5, 0.5]])),
    )
    assert decode(encode(several)).same_as(several)
    values = FoldPredictions(np.array([7, 3]), values=np.array([[1.5, -2.0], [np.pi, np.e]]))
    assert decode(encode(values)).same_as(values)
    assert not decode(encode(values)).same_as(several)


def _blob(header: dict, raw: bytes) -> bytes:
    text = json.dumps(header).encode()
    return b"TBFP" + struct.pack("<I", len(text)) + text + zlib.compress(raw)


def _rows(dtype: str, shape: list[int], raw: bytes, *, size: int | None = None) -> bytes:
    """A blob of 2 rows and one array ``indices`` as described, ``size`` its header's bytes."""
    array = {"name": "indices", "dtype": dtype, "shape": shape}
    header = {"version": 1, "n": 2, "arrays": [array], "compression": "zlib"}
    return _blob({**header, "raw": len(raw) if size is None else size}, raw)


@pytest.mark.parametrize(
    ("blob", "message"),
    [
        (b"\x80\x04\x95", "not an encoding of fold predictions"),  # a pickle's first bytes
        (b"TBFP\xff\xff\xff\x00{}", "a header longer than the blob"),
        (
            _blob(
                {"version": VERSION + 1, "n": 0, "arrays": [], "raw": 0, "compression": "z"}, b""
            ),
            f"version {VERSION + 1}",
        ),
        (_blob({"version": 1}, b""), "an unreadable header"),
        (_rows("|O", [2], bytes(16)), "array 'indices' of type |O"),
        (_rows("<i8", [3], bytes(24)), "shape \\[3\\] for 2 rows"),
        (_rows("<i8", [2], bytes(32), size=16), "arrays of another size"),
        (_rows("<i8", [2], bytes(16)), "either labels or values"),
    ],
)
def test_a_damaged_or_foreign_blob_is_refused_in_one_line(blob: bytes, message: str) -> None:
    with pytest.raises(DataFormatError, match=message) as refused:
        decode(blob)
    assert "\n" not in str(refused.value)


def test_a_truncated_blob_is_refused() -> None:
    blob = encode(FoldPredictions.of_classes(np.arange(40), np.arange(40) % 3, None))
    with pytest.raises(DataFormatError):
        decode(blob[:-5])
