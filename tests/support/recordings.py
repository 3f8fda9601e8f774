"""Recordings and windows made in the test: tactile takes, simulated contact-microphone
sessions extracted into a data set, and data sets whose instances are windows of
recordings."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tests.support.csvfiles import write_biotac_csv
from touchbench.app.schemas.extraction import ExtractRequest
from touchbench.app.services.extraction import extract_and_store
from touchbench.app.services.simulation import write_labels, write_session
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import add_dataset
from touchbench.benchmark.dataset import Attribute, Dataset, Schema


def extract_sessions(store: Store, folder: Path, *, sessions: int, touches: int) -> None:
    """``sessions`` simulated 3-microphone sessions (``s0.wav``, ...) of ``touches`` labelled
    touches each, written to ``folder`` and extracted into the data set ``touch``."""
    recordings, rows = [], []
    for seed in range(sessions):
        wav, labelled = write_session(folder, f"s{seed}", n_touches=touches, seed=seed)
        recordings.append(wav)
        rows += [(wav.name, *touch) for touch in labelled]
    labels = write_labels(folder / "labels.csv", rows)
    extract_and_store(store, ExtractRequest(recordings=recordings, labels=labels, name="touch"))


def write_take(path: Path, kind: str, seed: int) -> np.ndarray:
    """Three channels, 6 s: a 12 Hz vibration when slipping, noise when still."""
    rng = np.random.default_rng(seed)
    t = np.arange(600) / RATE
    samples = 0.1 * rng.standard_normal((3, 600))
    if kind == "slip":
        samples += np.sin(2 * np.pi * 12 * t)
    write_biotac_csv(path, samples, rate=RATE, seed=seed, jitter=0.003)
    return samples


PER_RECORDING = "scored per recording: each test recording's windows pooled"


def recorded_windows(*, recordings: int = 16, windows: int = 16, mixed: bool = False) -> Dataset:
    """Windows whose one feature is their recording's class plus noise as large as the
    gap between classes: a window is often wrong, the mean of a recording's windows rarely.

    ``mixed``: one recording holds windows of both classes.
    """
    rng = np.random.default_rng(5)
    label = np.repeat(np.arange(recordings) % 2, windows)
    noise = rng.normal(scale=0.8, size=(label.size, 2))
    values = np.column_stack([label, label + noise[:, 0], noise[:, 1]]).astype(float)
    if mixed:
        values[1, 0] = 1 - values[1, 0]
    target = Attribute("gesture", "nominal", ("tap", "press"))
    schema = Schema(
        relation="takes",
        attributes=(target, Attribute("level", "numeric"), Attribute("hum", "numeric")),
        target_indices=(0,),
    )
    groups = np.array([f"take{i:02d}.wav" for i in np.repeat(np.arange(recordings), windows)])
    return Dataset(schema=schema, values=values, groups=groups.astype(object))


def store_dataset(url: str, dataset: Dataset, name: str) -> None:
    """Store ``dataset`` under ``name`` in the store at ``url``."""
    store = Store(url)
    try:
        add_dataset(store, dataset, sha256=name[0] * 64, name=name)
    finally:
        store.dispose()


RATE = 100.0
