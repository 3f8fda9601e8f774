"""The streaming engine against the whole-recording functions it must agree with."""

from __future__ import annotations

import numpy as np
import pytest

from tests.support.signals import click_train
from touchbench.drivers.simulated import SimulatedTouch, simulate_session
from touchbench.features.errors import FeatureError
from touchbench.features.event_streams import EventStream, open_event_stream
from touchbench.features.events import detect_events
from touchbench.features.extractors.base import Instances
from touchbench.features.history import History
from touchbench.features.recipe import Recipe
from touchbench.features.snr import snr_track
from touchbench.features.snr_stream import SnrStream

SAMPLERATE = 44100.0
BLOCKS = (100, 256, 1000, 4096, 1 << 20)


def _session(seed: int, *, duration: float = 12.0, samplerate: float = SAMPLERATE) -> np.ndarray:
    """A UC3M-style session: 3 microphones, taps and strokes close together."""
    return simulate_session(
        duration=duration, samplerate=samplerate, n_touches=8, min_gap=0.6, seed=seed
    ).recording.samples


def _in_blocks(y: np.ndarray, length: int) -> list[np.ndarray]:
    return [y[:, start : start + length] for start in range(0, y.shape[1], length)]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_snr_stream_gives_the_whole_recording_track_whatever_the_blocks(seed: int) -> None:
    y = _session(seed)
    reference = snr_track(y, samplerate=SAMPLERATE)
    for length in BLOCKS:
        stream = SnrStream(3, samplerate=SAMPLERATE)
        touches = [t for block in _in_blocks(y, length) for t in stream.feed(block)]
        touches += stream.finish()
        touches.sort(key=lambda t: (t.first_window, t.channel))
        assert tuple(touches) == reference.touches
        assert np.array_equal(stream.level.view(0, stream.n_windows), reference.level)
        assert np.array_equal(stream.noise.view(0, stream.n_windows), reference.noise)


def test_digital_silence_clamps_the_floor_the_same_way_in_both() -> None:
    # The floor sinks below noise_min in the silence: the clamped recursion must not
    # depend on where blocks (or the batch tracker's chunks) begin.
    y = np.zeros((1, 44100 * 4))
    y[0, :44100] = 1e-4 * np.random.default_rng(0).standard_normal(44100)
    y[0, 3 * 44100 : 3 * 44100 + 2000] += 0.3
    reference = snr_track(y, samplerate=SAMPLERATE)
    assert reference.noise.min() == pytest.approx(1e-5)
    stream = SnrStream(1, samplerate=SAMPLERATE)
    touches = [t for block in _in_blocks(y, 777) for t in stream.feed(block)] + stream.finish()
    assert tuple(touches) == reference.touches and len(touches) == 1
    assert np.array_equal(stream.noise.view(0, stream.n_windows), reference.noise)


def _stream_events(stream: EventStream, y: np.ndarray, length: int) -> list:
    events = [event for block in _in_blocks(y, length) for event in stream.feed(block)]
    return events + stream.finish()


@pytest.mark.parametrize(
    ("kind", "options", "segment"),
    [
        ("snr", {}, None),
        ("snr", {"hangover": 0.2, "contact_gap": 0.01}, None),
        ("dbscan", {}, None),
        ("dbscan", {"eps": 0.02}, None),
        ("none", {}, 0.5),
        ("none", {}, None),
    ],
)
def test_event_streams_find_the_events_of_the_whole_recording(
    kind: str, options: dict, segment: float | None
) -> None:
    # DBSCAN clusters every ringing zero crossing of a tap: audio at 8 kHz keeps it quick.
    rate = 8000.0 if kind == "dbscan" else SAMPLERATE
    for seed in (0, 3):
        y = _session(seed, samplerate=rate)
        reference = detect_events(kind, y, samplerate=rate, segment=segment, options=options)
        for length in (333, 4096, 1 << 20):
            stream = open_event_stream(kind, 3, samplerate=rate, segment=segment, options=options)
            assert _stream_events(stream, y, length) == list(reference.events), (seed, length)
            assert stream.take_warnings() == list(reference.warnings)


def test_contacts_of_a_click_train_are_counted_as_in_the_whole_recording() -> None:
    y, _ = click_train(8.0, duration=3.0, samplerate=SAMPLERATE)
    reference = detect_events("snr", y[np.newaxis], samplerate=SAMPLERATE)
    stream = open_event_stream("snr", 1, samplerate=SAMPLERATE)
    events = _stream_events(stream, y[np.newaxis], 512)
    assert events == list(reference.events) and events[0].n_contacts > 5


RECIPES = [
    ("uc3m-audio", None, {}, None),
    ("uc3m-audio", "snr", {"hangover": 0.2, "wavelet_pitch": "true"}, None),
    ("uc3m-audio", "dbscan", {}, None),
    ("uc3m-audio", "none", {}, 1.0),
    ("mfcc", "snr", {}, None),
    ("mfcc", "none", {"n_mfcc": 10}, 0.5),
    ("window", "dbscan", {"length": 40}, None),
    ("sequence", "dbscan", {"length": 64, "baseline": 4}, None),
    ("sequence", "snr", {"length": 50, "resample": "true", "baseline": 8}, None),
    ("mfcc", "snr", {"frames": 12}, None),
    ("taxel-dft", "snr", {}, None),
    ("band-peaks", "none", {"bands": "0-120,500-550"}, 1.0),
]


def _whole(recipe: Recipe, y: np.ndarray, samplerate: float) -> Instances:
    detection = detect_events(
        recipe.events,
        y,
        samplerate=samplerate,
        segment=recipe.segment,
        options=recipe.event_options,
    )
    # The stream fills in the defaults that depend on the rate; so does the whole array.
    extractor = recipe.at_rate(samplerate)[0].make_extractor()
    instances = extractor.extract(y, samplerate=samplerate, detection=detection)
    instances.warnings = [*detection.warnings, *instances.warnings]
    return instances


def _streamed(recipe: Recipe, y: np.ndarray, samplerate: float, length: int) -> Instances:
    stream = recipe.open(samplerate=samplerate, n_channels=y.shape[0])
    parts = [stream.feed(block) for block in _in_blocks(y, length)]
    parts.append(stream.finish())
    return Instances.concat(parts, len(stream.feature_names))


@pytest.mark.parametrize(("extractor", "events", "options", "segment"), RECIPES)
@pytest.mark.slow
def test_streaming_gives_the_instances_of_whole_array_extraction(
    extractor: str, events: str | None, options: dict, segment: float | None
) -> None:
    recipe = Recipe.resolve(extractor, events=events, options=options, segment=segment)
    dbscan = recipe.events == "dbscan"  # slow on audio: shorter, or at 8 kHz where it may be
    rate = 8000.0 if dbscan and extractor != "uc3m-audio" else SAMPLERATE
    seeds = (0, 1) if extractor == "uc3m-audio" and not dbscan else (0,)
    for seed in seeds:
        y = _session(seed, duration=3.0 if dbscan else 12.0, samplerate=rate)
        reference = _whole(recipe, y, rate)
        assert reference.values.shape[0] > 0
        for length in (1000, 65536):
            got = _streamed(recipe, y, rate, length)
            assert np.array_equal(got.spans, reference.spans)
            assert np.array_equal(got.values, reference.values)
            assert got.meta == reference.meta
            assert sorted(got.warnings) == sorted(reference.warnings)


def test_an_event_that_never_ends_is_cut_at_max_event_and_memory_stays_bounded() -> None:
    touch = SimulatedTouch(onset=0.5, duration=29.0, channels=(0,), kind="stroke", amplitude=0.3)
    y = simulate_session(duration=30.0, n_channels=1, touches=[touch], seed=0).recording.samples
    recipe = Recipe.resolve("uc3m-audio", max_event=5.0)
    stream = recipe.open(samplerate=SAMPLERATE, n_channels=1)
    parts, held = [], 0
    for block in _in_blocks(y, 4096):
        parts.append(stream.feed(block))
        held = max(held, stream.samples.stop - stream.samples.start)
    parts.append(stream.finish())
    instances = Instances.concat(parts, 33)
    lengths = (instances.spans[:, 1] - instances.spans[:, 0]) / SAMPLERATE
    assert len(lengths) >= 5 and lengths.max() <= 5.0 + 1e-9
    assert sum("longer than max_event (5 s) and was cut" in w for w in instances.warnings) >= 5
    assert held <= 5.5 * SAMPLERATE + 4096  # one event and a block, not the recording


@pytest.mark.parametrize("kind", ["dbscan", "none"])
def test_other_detectors_cut_long_events_too(kind: str) -> None:
    noise = np.random.default_rng(0).standard_normal((1, 100 * 60))
    y = np.concatenate([0.01 * noise[:, :200], noise[:, 200:]], axis=1)  # loud from 2 s on
    stream = open_event_stream(kind, 1, samplerate=100.0, max_event=10.0)
    events = _stream_events(stream, y, 250)
    assert events and max(e.offset - e.onset for e in events) <= 1000
    assert any("was cut" in warning for warning in stream.take_warnings())


def test_history_keeps_the_columns_it_was_not_told_to_forget() -> None:
    history = History(2)
    data = np.arange(2 * 5000, dtype=float).reshape(2, 5000)
    for start in range(0, 5000, 700):
        history.append(data[:, start : start + 700])
        history.discard_before(max(0, start - 1000))
        assert np.array_equal(
            history.view(history.start, history.stop), data[:, history.start : history.stop]
        )
    with pytest.raises(FeatureError, match="not in the history"):
        history.view(0, 10)


def test_a_recipe_survives_json_and_rejects_what_it_does_not_know() -> None:
    recipe = Recipe.resolve("band-peaks", options={"bands": "0-120,500-550", "vertical": "2"})
    again = Recipe.from_json(recipe.to_json())
    assert again == recipe and again.segment == 1.0 and again.events == "none"
    assert recipe.to_json()["extractor_options"]["bands"] == [[0.0, 120.0], [500.0, 550.0]]
    with pytest.raises(FeatureError, match="unknown option 'eps' for extractor 'uc3m-audio'"):
        Recipe.resolve("uc3m-audio", options={"eps": 1})
    with pytest.raises(FeatureError, match="not an extraction recipe"):
        Recipe.from_json({"extractor": "mfcc"})
    with pytest.raises(FeatureError, match="segment length only applies"):
        Recipe.resolve("uc3m-audio", segment=1.0)


def test_a_stream_refuses_blocks_of_another_channel_count_and_nan() -> None:
    stream = Recipe.resolve("uc3m-audio").open(samplerate=SAMPLERATE, n_channels=3)
    with pytest.raises(FeatureError, match=r"shape \(3, n_samples\)"):
        stream.feed(np.zeros((2, 100)))
    bad = np.zeros((3, 100))
    bad[1, 5] = np.nan
    with pytest.raises(FeatureError, match="NaN"):
        stream.feed(bad)
    # A stream shorter than one window gives nothing, with a warning (not an error: the
    # other recordings of an extraction still count).
    short = Recipe.resolve("uc3m-audio").open(samplerate=SAMPLERATE, n_channels=3)
    short.feed(np.zeros((3, 100)))
    left_out = short.finish()
    assert left_out.values.shape == (0, 99)
    assert left_out.warnings == [
        "lasts 100 samples, shorter than one 'uc3m-audio' window of 256; it was left out"
    ]
