"""Recording labelled takes from a sound card into a session folder.

A session folder holds one WAV file per take (``take-001.wav``, ...) and ``labels.csv``
(``file,TARGET...``: every touch of a take has the take's labels), which is what
``touchbench extract`` reads.  A take is written to ``take-NNN.wav.part`` and renamed
when it ends, and the labels file is replaced whole, so a Ctrl-C keeps the audio so far
and a kill at any moment leaves the labels file valid (at worst a ``.part`` file).  The
labels file is read as a stream (its header line bounded, its rows copied block by
block), never whole.
"""

from __future__ import annotations

import csv
import io
import os
import shutil
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

import soundfile

from touchbench.app.errors import AppError
from touchbench.benchmark.io.csv import csv_problem
from touchbench.drivers.errors import DriverError
from touchbench.drivers.limits import LINE_CHARS, LineTooLongError, bounded_lines
from touchbench.drivers.sound import SoundDeviceSource
from touchbench.features.event_streams import open_event_stream

LABELS = "labels.csv"


@dataclass(frozen=True)
class Take:
    """A recorded take: its file, the labels file, its length, what happened."""

    path: Path
    labels: Path
    seconds: float
    touches: int
    overflows: int
    interrupted: bool


def record_take(
    folder: Path,
    *,
    device: str | int,
    samplerate: float | None = None,
    channels: int | None = None,
    seconds: float | None = None,
    labels: Mapping[str, str] | None = None,
    on_touch: Callable[[float, float, tuple[int, ...]], None] | None = None,
) -> Take:
    """Record one take from ``device`` into ``folder`` and label it.

    Touches are detected as the audio arrives (the ``snr`` detector of the streaming
    engine) and reported through ``on_touch(start, end, channels)``.  Recording stops
    after ``seconds`` of audio, or at Ctrl-C (then ``interrupted`` is true).
    """
    labels = dict(labels or {})
    labels_path = folder / LABELS
    header = _check_header(labels_path, list(labels)) if labels else []
    source = SoundDeviceSource(device, samplerate=samplerate, channels=channels, seconds=seconds)
    folder.mkdir(parents=True, exist_ok=True)  # only once the device is known to work
    path = _next_take(folder)
    part = path.with_name(path.name + ".part")
    detector = open_event_stream("snr", source.n_channels, samplerate=source.samplerate)
    rate = source.samplerate
    count, touches, interrupted = 0, 0, False

    def report(events: list) -> int:
        for event in events:
            if on_touch is not None:
                on_touch(event.onset / rate, event.offset / rate, event.channels)
        return len(events)

    with (
        source,
        soundfile.SoundFile(
            part,
            "w",
            samplerate=round(rate),
            channels=source.n_channels,
            subtype="FLOAT",
            format="WAV",
        ) as wav,
    ):
        try:
            for block in source.blocks():
                wav.write(block.samples.T)
                count += block.samples.shape[1]
                touches += report(detector.feed(block.samples))
        except KeyboardInterrupt:
            interrupted = True
    if count == 0:
        part.unlink(missing_ok=True)
        raise DriverError(f"{source.name}: no audio was captured")
    touches += report(detector.finish())
    os.replace(part, path)
    if labels:
        _append_row(labels_path, header, [path.name, *labels.values()])
    return Take(path, labels_path, count / rate, touches, source.overflows, interrupted)


def _check_header(labels_path: Path, targets: list[str]) -> list[str]:
    header = ["file", *targets]
    if labels_path.exists():
        try:
            with labels_path.open(newline="", encoding="utf-8") as handle:
                lines = bounded_lines(handle, limit=LINE_CHARS, source=str(labels_path))
                found = next(csv.reader(lines), [])
        except csv.Error as error:
            raise AppError(f"{labels_path}: {csv_problem(error)} on its first line") from None
        except LineTooLongError as error:
            raise AppError(str(error)) from None
        if found != header:
            raise AppError(
                f"{labels_path} labels takes with {','.join(found[1:]) or 'no target'}; "
                f"record with the same label targets (got {','.join(targets) or 'none'}) or "
                "into another folder"
            )
    return header


def _next_take(folder: Path) -> Path:
    number = 1
    while (folder / f"take-{number:03d}.wav").exists():
        number += 1
    return folder / f"take-{number:03d}.wav"


def _append_row(labels_path: Path, header: list[str], row: list[str]) -> None:
    """Add a row to the labels file by replacing it (never half-written): its rows are
    copied block by block into a new file, the new row written after them."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    temporary = labels_path.with_name(labels_path.name + ".tmp")
    with temporary.open("wb") as out:
        if labels_path.exists():
            with labels_path.open("rb") as old:
                shutil.copyfileobj(old, out)
                if out.tell() and not _ends_a_line(old):
                    out.write(b"\n")
        if out.tell() == 0:
            writer.writerow(header)
        writer.writerow(row)
        out.write(buffer.getvalue().encode("utf-8"))
    os.replace(temporary, labels_path)


def _ends_a_line(handle: io.BufferedReader) -> bool:
    """Whether the file read to its end by ``handle`` ends with a line break."""
    handle.seek(-1, os.SEEK_END)
    return handle.read(1) in (b"\n", b"\r")
