"""Defaults that depend on the recordings: taxel-dft's dropped bins by sample rate, the
sequence extractor's whole recordings, and options listed with their types."""

from __future__ import annotations

import numpy as np
import pytest

from touchbench.features.errors import FeatureError
from touchbench.features.events import Detection, Event
from touchbench.features.extractors import EXTRACTORS, make_extractor
from touchbench.features.recipe import Recipe


@pytest.mark.parametrize(("rate", "drop"), [(800.0, 4), (750.0, 4), (400.0, 4), (100.0, 1)])
def test_taxel_dft_drops_the_published_bins_at_its_rates_and_only_dc_at_100_hz(
    rate: float, drop: int
) -> None:
    recipe, notes = Recipe.resolve("taxel-dft").at_rate(rate)
    assert recipe.extractor_options["drop"] == drop
    assert notes == [
        f"extractor 'taxel-dft': drop={drop} at {rate:g} Hz "
        "(4 from 400 Hz up (as published), else 1 (DC only))"
    ]
    assert recipe.make_extractor().feature_names(1)[0] == f"dft{drop}_1"


def test_a_given_drop_is_kept_and_zero_keeps_the_dc_bin() -> None:
    recipe, notes = Recipe.resolve("taxel-dft", options={"drop": "0"}).at_rate(100.0)
    assert recipe.extractor_options["drop"] == 0 and notes == []
    extractor = recipe.make_extractor()
    y = np.random.default_rng(0).standard_normal((2, 64))
    instances = extractor.extract(y, samplerate=100.0, detection=Detection((Event(0, 64, (0,)),)))
    # Bin 0 of a rectangular DFT is the sum of the window.
    assert instances.values[0, 0] == pytest.approx(y[0].sum())
    assert instances.values.shape == (1, 2 * 32)
    with pytest.raises(FeatureError, match="option 'drop' of extractor 'taxel-dft': must be"):
        Recipe.resolve("taxel-dft", options={"drop": "-1"})


def test_taxel_dft_in_batches_matches_one_transform_of_every_window() -> None:
    y = np.random.default_rng(1).standard_normal((3, 8 * 700 + 64))
    extractor = make_extractor("taxel-dft", samplerate=800.0)
    instances = extractor.extract(
        y, samplerate=800.0, detection=Detection((Event(0, y.shape[1], (0, 1, 2)),))
    )
    assert instances.values.shape == (701, 3 * 28)  # more windows than one batch
    last = np.fft.fft(y[:, 5600:5664], axis=1).real[:, 4:32]
    assert np.allclose(instances.values[700], last.reshape(-1))
    assert list(instances.spans[700]) == [5600, 5664]


def test_the_sequence_of_whole_recordings_takes_the_longest_and_pads() -> None:
    recipe = Recipe.resolve("sequence", events="none")
    assert recipe.needs_longest()
    with pytest.raises(FeatureError, match="with events 'none' needs a length"):
        recipe.at_rate(100.0)
    filled, notes = recipe.at_rate(100.0, longest=300)
    assert (filled.extractor_options["length"], filled.extractor_options["pad"]) == (300, True)
    assert notes == [
        "extractor 'sequence': length=300 samples (3 s), the longest recording; shorter ones "
        "are padded with their last sample"
    ]
    stream = filled.open(samplerate=100.0, n_channels=1)
    stream.feed(np.arange(200.0)[np.newaxis, :])
    instances = stream.finish()
    assert instances.values.shape == (1, 300)
    assert np.array_equal(instances.values[0, :200], np.arange(200.0))
    assert np.all(instances.values[0, 200:] == 199.0)


def test_a_given_length_cuts_or_pads_whole_recordings_and_segments_give_theirs() -> None:
    given = Recipe.resolve("sequence", events="none", options={"length": 50})
    assert not given.needs_longest()
    filled, notes = given.at_rate(100.0)
    assert (filled.extractor_options["length"], filled.extractor_options["pad"]) == (50, True)
    assert notes == ["extractor 'sequence': each recording is cut or padded to length=50 samples"]
    segments, notes = Recipe.resolve("sequence", events="none", segment=0.5).at_rate(100.0)
    assert segments.extractor_options["length"] == 50 and notes == []
    detected, notes = Recipe.resolve("sequence").at_rate(100.0)
    assert (
        detected.extractor_options["length"] == 256 and detected.extractor_options["pad"] is False
    )


def test_every_option_says_its_type_and_meaning() -> None:
    for kind in EXTRACTORS.values():
        for option in kind.options:
            assert option.kind and option.help, (kind.name, option.name)
            assert (
                option.default is not None
                or option.default_text
                or option.name
                in {
                    "vertical",
                    "frames",
                }
            ), (kind.name, option.name)
