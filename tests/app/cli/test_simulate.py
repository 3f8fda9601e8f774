"""`touchbench simulate`: both simulated sensors write what `extract` reads, and the
oscillating link teaches something without being trivially separable."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from sklearn.ensemble import RandomForestClassifier
from sklearn.model_selection import GroupKFold, cross_val_score

from tests.support.cli_runner import run_cli
from touchbench.app.services.extraction import extract_dataset
from touchbench.drivers.oscillating import CONTACTS, simulate_link_trial


def test_simulate_contact_mic_writes_sessions_extract_reads(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    db = f"sqlite:///{tmp_path / 't.db'}"
    out = tmp_path / "mic"
    written = run_cli(
        capsys, db, "simulate", "contact-mic", "--out", str(out), "--trials", "2", "--json"
    ).json()
    assert [Path(p).name for p in written["recordings"]] == ["session1.wav", "session2.wav"]
    summary = run_cli(
        capsys, db, "extract", *written["recordings"], "--labels", written["labels"], "--json"
    ).json()
    assert summary["events_found"] == summary["events_labelled"] == 32
    assert summary["targets"] == ["gesture", "place"]


def test_link_trials_are_seeded_and_differ_between_trials() -> None:
    first = simulate_link_trial("p2", seed=4).recording
    assert np.array_equal(first.samples, simulate_link_trial("p2", seed=4).recording.samples)
    assert not np.array_equal(first.samples, simulate_link_trial("p2", seed=5).recording.samples)
    assert first.samples.shape == (3, 9600) and first.samplerate == 3200.0


def test_the_link_contact_shifts_the_modes_up() -> None:
    def peak(contact: str) -> float:
        vertical = [simulate_link_trial(contact, seed=s).recording.samples[2] for s in range(8)]
        spectrum = np.mean([np.abs(np.fft.rfft(x - x.mean())) for x in vertical], axis=0)
        frequencies = np.fft.rfftfreq(vertical[0].size, 1 / 3200)
        band = (frequencies > 30) & (frequencies < 120)
        return float(frequencies[band][np.argmax(spectrum[band])])

    # The first mode stiffens more the nearer the contact is to the tip (p1, by the clamp,
    # barely moves it: the higher modes tell p1 from no contact).
    assert peak("none") < peak("p2") < peak("p3") < peak("p4") < peak("p5")


@pytest.mark.parametrize("extractor", ["band-peaks", "mfcc"])
def test_oscillating_link_contacts_are_learnt_but_not_trivially(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, extractor: str
) -> None:
    db = f"sqlite:///{tmp_path / 't.db'}"
    written = run_cli(
        capsys,
        db,
        "simulate",
        "oscillating-link",
        "--out",
        str(tmp_path / "l"),
        "--trials",
        "48",
        "--seed",
        "3",
        "--json",
    ).json()
    data = extract_dataset(
        [Path(p) for p in written["recordings"]],
        labels=Path(written["labels"]),
        extractor=extractor,
        segment=1.0,
        events="none",
        # At 3200 Hz, 30 ms frames have 33 Hz bins: too coarse for the first mode's shift.
        options={"frame": 0.25, "hop": 0.05} if extractor == "mfcc" else None,
    ).dataset
    assert data.n_instances == 48 * 3
    assert data.schema.targets[0].values == CONTACTS
    accuracy = cross_val_score(
        RandomForestClassifier(n_estimators=100, random_state=0),
        data.X,
        data.Y[:, 0],
        groups=data.groups,
        cv=GroupKFold(n_splits=4),
    ).mean()
    # Six classes: chance is 0.17; the trials' variation keeps it from 1.
    assert 0.45 < accuracy < 0.97, accuracy
