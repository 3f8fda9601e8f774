"""Simulated, labelled recordings written as WAV files plus a labels CSV: the input of the
demo, of ``touchbench simulate`` and of the extraction tests.

``contact-mic``: sessions of taps and strokes on three contact microphones (44.1 kHz),
labelled by interval with gesture and place.  ``oscillating-link``: trials of an
actively oscillated link with a 3-axis accelerometer (3200 Hz, :mod:`drivers.oscillating`),
labelled by file with the contact point.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import soundfile

from touchbench.drivers.oscillating import CONTACTS, simulate_link_trial
from touchbench.drivers.oscillating import SAMPLERATE as LINK_RATE
from touchbench.drivers.simulated import SimulatedSession, SimulatedTouch, simulate_session

SAMPLERATE = 44100
#: Microphone i sits nearest place i, so a touch there is heard on channel i.
PLACES = ("head", "left_arm", "right_arm")
GESTURE_SECONDS = {"tap": (0.02, 0.1), "stroke": (0.3, 0.9)}


def contact_mic_take(
    *, n_touches: int, seed: int
) -> tuple[SimulatedSession, list[tuple[float, float, str, str]]]:
    """One simulated 3-microphone session in memory, and its true touches.

    Returns
    -------
    session : SimulatedSession
        Its recording has shape (3, n_samples) at :data:`SAMPLERATE`.
    touches : list of (start, end, gesture, place)
    """
    rng = np.random.default_rng(seed)
    touches: list[SimulatedTouch] = []
    labels: list[tuple[float, float, str, str]] = []
    onset = 0.5
    for _ in range(n_touches):
        gesture = str(rng.choice(list(GESTURE_SECONDS)))
        place = int(rng.integers(len(PLACES)))
        low, high = GESTURE_SECONDS[gesture]
        duration = float(rng.uniform(low, high))
        touches.append(
            SimulatedTouch(
                onset=onset,
                duration=duration,
                channels=(place,),
                kind=gesture,  # type: ignore[arg-type]
                amplitude=float(rng.uniform(0.15, 0.4)),
            )
        )
        labels.append((onset, onset + duration, gesture, PLACES[place]))
        onset += duration + float(rng.uniform(1.2, 1.8))  # quiet longer than the hangover
    session = simulate_session(
        duration=onset + 0.5,
        samplerate=SAMPLERATE,
        n_channels=len(PLACES),
        touches=touches,
        seed=seed,
    )
    return session, labels


def write_session(
    folder: Path, name: str, *, n_touches: int, seed: int
) -> tuple[Path, list[tuple[float, float, str, str]]]:
    """One simulated 3-microphone session (:func:`contact_mic_take`) as a WAV file, and its
    true touches.

    Returns
    -------
    path : Path
    touches : list of (start, end, gesture, place)
    """
    session, labels = contact_mic_take(n_touches=n_touches, seed=seed)
    path = folder / f"{name}.wav"
    soundfile.write(path, session.recording.samples.T, SAMPLERATE, subtype="FLOAT")
    return path, labels


def write_labels(path: Path, rows: list[tuple[str, float, float, str, str]]) -> Path:
    with path.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(["file", "start", "end", "gesture", "place"])
        for file, start, end, gesture, place in rows:
            writer.writerow([file, f"{start:.3f}", f"{end:.3f}", gesture, place])
    return path


def write_contact_mic_sessions(
    folder: Path, *, trials: int, seed: int = 0, n_touches: int = 16
) -> tuple[list[Path], Path]:
    """``trials`` simulated contact-microphone sessions of ``n_touches`` touches and their
    labels CSV (``file,start,end,gesture,place``)."""
    folder.mkdir(parents=True, exist_ok=True)
    paths, rows = [], []
    for trial in range(trials):
        path, touches = write_session(
            folder, f"session{trial + 1}", n_touches=n_touches, seed=seed + trial
        )
        paths.append(path)
        rows += [(path.name, *touch) for touch in touches]
    return paths, write_labels(folder / "labels.csv", rows)


def write_link_trials(folder: Path, *, trials: int, seed: int = 0) -> tuple[list[Path], Path]:
    """``trials`` simulated oscillating-link trials (3 s, 3200 Hz, 3 axes), the contact
    classes in turn, and their labels CSV (``file,contact``: every second of a trial is
    labelled with its contact)."""
    folder.mkdir(parents=True, exist_ok=True)
    paths, lines = [], ["file,contact"]
    for trial in range(trials):
        contact = CONTACTS[trial % len(CONTACTS)]
        link = simulate_link_trial(contact, seed=seed * 100_003 + trial)
        path = folder / f"trial{trial + 1:03d}.wav"
        soundfile.write(path, link.recording.samples.T, int(LINK_RATE), subtype="FLOAT")
        paths.append(path)
        lines.append(f"{path.name},{contact}")
    labels = folder / "labels.csv"
    labels.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return paths, labels
