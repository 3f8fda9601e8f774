"""ROS bags other people's tools wrote: jsk_3rdparty's audio_common test bags (ROS 1, raw
16 kHz S16LE speech published by audio_capture-like nodes, no AudioInfo topic).

The bags are not in this repository (third-party data): put them in
``../shared/datasets/ros-bags/`` beside the repository, or in the folder named by
``TOUCHBENCH_PUBLIC_BAGS``; the tests skip where they are absent.  Where they come from
is in docs/bags.md.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import SHARED_DATASETS
from touchbench.drivers.errors import DriverError
from touchbench.drivers.replay import FileReplaySource

FOLDER = Path(os.environ.get("TOUCHBENCH_PUBLIC_BAGS", SHARED_DATASETS / "ros-bags"))
PCM = {"samplerate": 16000, "channels": 1, "sample_format": "S16LE"}


def public_bag(name: str) -> Path:
    """A public bag by file name; skips the test when it is not there."""
    path = FOLDER / name
    if not path.is_file():
        pytest.skip(
            f"the public bag {name} is not in {FOLDER} (see docs/bags.md for where "
            "to get it, or set TOUCHBENCH_PUBLIC_BAGS)"
        )
    return path


@pytest.mark.parametrize(
    ("name", "topic", "n_samples"),
    [("wave.bag", "/audio", 477 * 160), ("konnichiwa.bag", "/speech_audio", 74176)],
)
def test_jsk_speech_bags_are_read_as_raw_pcm_given_its_format(
    name: str, topic: str, n_samples: int
) -> None:
    bag = public_bag(name)
    with pytest.raises(DriverError, match=f"the audio of '{topic}' is not MP3, so its format"):
        FileReplaySource(bag)
    with FileReplaySource(bag, **PCM) as source:  # type: ignore[arg-type]
        samples = np.concatenate([block.samples for block in source.blocks()], axis=1)[0]
    assert samples.size == n_samples
    # Speech at 16 kHz read as its true format is smooth from sample to sample; the same
    # bytes read as another format are not as smooth.
    assert np.corrcoef(samples[:-1], samples[1:])[0, 1] > 0.9
    assert 0.01 < np.sqrt(np.mean(samples**2)) < 0.5


def test_the_audio_spans_the_bag_as_16_khz_says() -> None:
    """wave.bag's 477 messages of 160 samples span its 4.76 s at 16 kHz: the rate is right."""
    bag = public_bag("wave.bag")
    with FileReplaySource(bag, **PCM) as source:  # type: ignore[arg-type]
        blocks = list(source.blocks())
    assert blocks[-1].time == pytest.approx(4.76, abs=0.05)
    assert (blocks[-1].time + 160 / 16000) - blocks[0].time == pytest.approx(4.77, abs=0.05)
