"""Sources the service reads itself for a live session (the live view's): recordings
uploaded for replay, kept under the work folder, and a simulated sensor.

A client names the source (:class:`app.schemas.live.LiveSource`); the service opens it
here, bounded by its settings: a source longer than ``live_source_seconds`` is refused
before a sample is read, and only the newest ``live_replays`` uploads are kept.
"""

from __future__ import annotations

import json
import shutil
import uuid
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from touchbench.app.errors import USER_ERRORS, AppError, NotFoundError, client_words
from touchbench.app.schemas.live import LiveReplay, LiveSource
from touchbench.app.services.simulation import (
    GESTURE_SECONDS,
    PLACES,
    SAMPLERATE,
    contact_mic_take,
)
from touchbench.drivers.errors import DriverError
from touchbench.drivers.replay import FileReplaySource
from touchbench.drivers.source import LIVE_BLOCK, Block, Source

#: The folder of the work folder where uploaded replays are kept, one folder each.
REPLAYS = "live-replays"
#: What a replay's folder says of it, beside the recording.
ABOUT = "replay.json"
#: Blocks last at most this many seconds, so that touches are marked soon after they end
#: whatever the sample rate (:data:`drivers.source.LIVE_BLOCK` samples at audio rates).
BLOCK_SECONDS = 0.012
#: The longest a simulated sensor's take can be per touch: the longest gesture, the longest
#: quiet after it and the half seconds before and after
#: (:func:`app.services.simulation.contact_mic_take`), so its length is bounded before it
#: is made.
SECONDS_PER_TOUCH = max(high for _, high in GESTURE_SECONDS.values()) + 1.8 + 1.0
#: Read from a recording at a time while measuring it.
MEASURE_BLOCK = 1 << 16


def block_length(samplerate: float) -> int:
    """Samples per block of a live source at ``samplerate`` Hz."""
    return max(1, min(LIVE_BLOCK, int(samplerate * BLOCK_SECONDS)))


def replay_folder(work_dir: Path) -> Path:
    return work_dir / REPLAYS


def save_replay(folder: Path, name: str, *, max_seconds: float, keep: int) -> LiveReplay:
    """Check and keep a recording saved in ``folder`` (a new folder of
    :func:`replay_folder`, named by a fresh id) for replay; remove the oldest replays
    beyond ``keep``.  The folder is removed when the recording is refused.

    Parameters
    ----------
    folder : Path
        Holds the recording alone, under ``name``.
    name : str
        The file's name, as the client sent it (its safe form).
    max_seconds : float
        Longest recording taken (``live_source_seconds``).
    keep : int
        Replays kept at most (``live_replays``).

    Raises
    ------
    AppError
        Not a recording touchbench reads, no samples, or longer than ``max_seconds``.
    """
    try:
        with FileReplaySource(folder / name, block_length=MEASURE_BLOCK) as source:
            samples = 0
            for block in source.blocks():
                samples += block.samples.shape[1]
                if samples > max_seconds * source.samplerate:
                    raise AppError(
                        f"{name}: the recording is longer than {max_seconds:g} s, the longest "
                        "a live source may be (TOUCHBENCH_LIVE_SOURCE_SECONDS)"
                    )
            replay = LiveReplay(
                id=folder.name,
                name=name,
                seconds=samples / source.samplerate,
                samplerate=source.samplerate,
                channels=source.n_channels,
            )
    except USER_ERRORS as error:  # said of the client's file, never of the service's folder
        shutil.rmtree(folder, ignore_errors=True)
        raise AppError(client_words(str(error), str(folder))) from None
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)
        raise
    (folder / ABOUT).write_text(json.dumps(replay.to_json()), encoding="utf-8")
    for old in list_replays(folder.parent)[keep:]:
        shutil.rmtree(folder.parent / old.id, ignore_errors=True)
    return replay


def new_replay_folder(work_dir: Path) -> Path:
    """A fresh folder for an upload (:func:`save_replay` checks and keeps it)."""
    folder = replay_folder(work_dir) / uuid.uuid4().hex
    folder.mkdir(parents=True)
    return folder


def list_replays(folder: Path) -> list[LiveReplay]:
    """The replays kept in ``folder`` (:func:`replay_folder`), newest first."""
    found = []
    for about in folder.glob(f"*/{ABOUT}"):
        try:
            replay = LiveReplay.model_validate_json(about.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            continue  # being written or removed meanwhile
        found.append((about.stat().st_mtime, replay))
    return [replay for _, replay in sorted(found, key=lambda item: -item[0])]


def open_source(work_dir: Path, spec: LiveSource, *, max_seconds: float) -> Source:
    """The source ``spec`` names, in blocks of :func:`block_length`.

    Raises
    ------
    NotFoundError
        No replay of that id (never uploaded, or removed as the oldest).
    AppError
        A simulated take that could be longer than ``max_seconds``.
    """
    if spec.kind == "replay":
        folder = replay_folder(work_dir) / str(spec.replay)
        about = folder / ABOUT
        if not about.is_file():
            raise NotFoundError(f"no uploaded recording '{spec.replay}' (upload it again)")
        replay = LiveReplay.model_validate_json(about.read_text(encoding="utf-8"))
        try:
            return FileReplaySource(
                folder / replay.name, block_length=block_length(replay.samplerate)
            )
        except DriverError as error:
            raise AppError(f"{replay.name}: {error}") from None
    longest = spec.touches * SECONDS_PER_TOUCH
    if longest > max_seconds:
        raise AppError(  # short: a WebSocket's close reason holds 123 bytes
            f"source.touches: {spec.touches} touches may last {longest:g} s, over the "
            f"{max_seconds:g} s of TOUCHBENCH_LIVE_SOURCE_SECONDS"
        )
    return SimulatedSensor(touches=spec.touches, seed=spec.seed)


class SimulatedSensor(Source):
    """Three contact microphones at 44.1 kHz touched ``touches`` times: one simulated take
    (:func:`app.services.simulation.contact_mic_take`) of one touch after another, each made
    when its turn comes, so that memory holds one touch's seconds whatever the length.

    Parameters
    ----------
    touches : int
    seed : int
        The take of touch ``i`` is drawn from ``seed * 1_000_003 + i``.
    """

    def __init__(self, *, touches: int, seed: int) -> None:
        self.touches = touches
        self.seed = seed
        self.samplerate = float(SAMPLERATE)
        self.n_channels = len(PLACES)
        self.name = f"simulated sensor ({touches} touches, seed {seed})"

    def blocks(self) -> Iterator[Block]:
        length = block_length(self.samplerate)
        offset = 0
        for i in range(self.touches):
            take, _ = contact_mic_take(n_touches=1, seed=self.seed * 1_000_003 + i)
            samples = take.recording.samples
            for start in range(0, samples.shape[1], length):
                yield Block(samples[:, start : start + length], (offset + start) / self.samplerate)
            offset += samples.shape[1]


def peaks(samples: np.ndarray) -> list[float]:
    """The largest magnitude of each channel of a block, shape (n_channels, n) to
    (n_channels,): the signal the live view scrolls, one column per block."""
    return [round(float(value), 5) for value in np.abs(samples).max(axis=1)]
