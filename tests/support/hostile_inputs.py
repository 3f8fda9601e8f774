"""Inputs a hostile (or unlucky) client sends, made in the test (issue 36): small files whose
values ask for much work, a deeply nested JSON body, a results file of thousands of
classifiers, whole tactile recordings as sequences.  Shared by the tests and
``perf/hostile.py``."""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: A name that lists as another one: ``abc`` followed by a right-to-left override.
RLO_NAME = "touch\u202edcba"


def gap_csv(path: Path, *, jump: float = 3000.0) -> Path:
    """A CSV of a few rows at 1 kHz whose stamps jump by ``jump`` seconds (about 150 bytes):
    resampling would fill the jump with ``jump * 1000`` samples."""
    rows = ["time,ch1,ch2"]
    times = [0.0, 0.001, 0.002, 0.003, 0.004, jump + 0.005, jump + 0.006, jump + 0.007]
    rows += [f"{t:.3f},{np.sin(i):.4f},{np.cos(i):.4f}" for i, t in enumerate(times)]
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    return path


def nan_stamp_csv(path: Path) -> Path:
    """A timed CSV whose third stamp is NaN (line 4)."""
    rows = ["time,ch1,ch2", "0.000,1,2", "0.001,1,2", "nan,1,2", "0.003,1,2", "0.004,1,2"]
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    return path


def one_line_csv(path: Path, *, megabytes: float = 20.0) -> Path:
    """A CSV file of one line of numbers and no line break, ``megabytes`` long."""
    field = b"0.5,"
    with path.open("wb") as out:
        chunk = field * (1 << 16)
        for _ in range(int(megabytes * 2**20) // len(chunk)):
            out.write(chunk)
    return path


def deep_json(depth: int = 100_000) -> bytes:
    """A prediction body whose first instance is a list nested ``depth`` deep."""
    return b'{"instances": [' + b"[" * depth + b"]" * depth + b"]}"


def results_arff(path: Path, *, n_classifiers: int, n_instances: int = 90, folds: int = 10) -> Path:
    """A WEKA Experimenter results file (InstanceResultListener) of ``n_classifiers``
    schemes (``c0000``...) on a data set of ``n_instances`` instances of three classes,
    ``folds`` folds each, as an imported paper's results would be.

    A few distinct classifiers are made by :func:`results_to_dataset`, and their rows
    written again under the other names (the file is made in a second, not a minute).
    """
    from touchbench.benchmark.evaluation.results_arff import results_to_dataset
    from touchbench.benchmark.io.arff import dumps_arff
    from touchbench.benchmark.results import TaskKey, TaskResult

    distinct = min(n_classifiers, 20)
    random = np.random.default_rng(0)
    results = []
    per_fold = n_instances // folds
    for index in range(distinct):
        for fold in range(folds):
            right = random.integers(0, per_fold // 3 + 1, size=3)
            confusion = np.diag(right)
            confusion[0, 1] += per_fold - int(right.sum())  # the rest of the fold: errors
            accuracy = float(np.trace(confusion)) / per_fold
            metrics = {"accuracy": accuracy, "f1_weighted": accuracy, "kappa": accuracy - 0.3}
            key = TaskKey(f"c{index:04d}", 0, fold)
            results.append(
                TaskResult(
                    key, "ok", None, metrics, confusion.tolist(), n_instances - per_fold, per_fold
                )
            )
    text = dumps_arff(
        results_to_dataset(results, dataset_name="touch", specs={}, scheme_names="id")
    )
    header, data = text.split("@data\n", 1)
    names = [f"c{index:04d}" for index in range(n_classifiers)]
    lines = []
    for line in header.splitlines():
        if line.startswith("@attribute Key_Scheme "):
            line = "@attribute Key_Scheme {" + ",".join(f"touchbench.{n}" for n in names) + "}"
        elif line.startswith("@attribute Key_Scheme_options "):
            line = "@attribute Key_Scheme_options {" + ",".join(f"'-id {n}'" for n in names) + "}"
        lines.append(line)
    lines.append("@data")
    for row in data.splitlines():
        if not row.strip():
            continue
        source = row.split(",")[3].removeprefix("touchbench.")
        for name in names[int(source[1:]) :: distinct]:
            lines.append(row.replace(source, name))
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def tactile_sequences(
    folder: Path, *, n_recordings: int = 200, n_channels: int = 44, n_samples: int = 800
) -> tuple[list[Path], Path]:
    """``n_recordings`` BioTac-like recordings (``.npy``, channels x samples) and a labels
    file (``file,object``): what extracting whole recordings as sequences reads."""
    folder.mkdir(parents=True, exist_ok=True)
    random = np.random.default_rng(1)
    paths, rows = [], ["file,object"]
    base = np.sin(np.linspace(0, 6, n_samples))
    for index in range(n_recordings):
        label = index % 4
        samples = base * (1 + label) + random.normal(0, 0.1, (n_channels, n_samples))
        path = folder / f"take-{index:03d}.npy"
        np.save(path, samples.astype(np.float64))
        paths.append(path)
        rows.append(f"{path.name},object{label}")
    labels = folder / "labels.csv"
    labels.write_text("\n".join(rows) + "\n", encoding="utf-8")
    return paths, labels


def timed_takes(folder: Path, *, n_takes: int = 6, n_rows: int = 200) -> tuple[list[Path], Path]:
    """Timed CSV recordings (``time,ch1,ch2`` at 1 kHz) of two states, and their labels
    file: what a model that predicts CSV recordings is trained on."""
    folder.mkdir(parents=True, exist_ok=True)
    random = np.random.default_rng(2)
    paths, rows = [], ["file,state"]
    for index in range(n_takes):
        state = ("still", "slip")[index % 2]
        values = random.normal(0, 1 + 3 * (index % 2), (n_rows, 2))
        lines = ["time,ch1,ch2"]
        lines += [f"{row / 1000:.3f},{a:.4f},{b:.4f}" for row, (a, b) in enumerate(values)]
        path = folder / f"take-{index}.csv"
        path.write_text("\n".join(lines) + "\n", encoding="utf-8")
        paths.append(path)
        rows.append(f"{path.name},{state}")
    labels = folder / "labels.csv"
    labels.write_text("\n".join(rows) + "\n", encoding="utf-8")
    return paths, labels


def long_labels(path: Path, *, n_rows: int) -> Path:
    """A labels file of ``n_rows`` intervals of one recording (``take-0.csv``)."""
    with path.open("w", encoding="utf-8") as out:
        out.write("file,start,end,state\n")
        for row in range(n_rows):
            out.write(f"take-0.csv,{row * 0.01:.2f},{row * 0.01 + 0.005:.3f},still\n")
    return path
