"""Synthetic touch sessions: a noise floor plus taps and strokes at known times.

A tap is a struck resonance, two exponentially decaying sinusoids (300 Hz to 3 kHz)
starting at the onset; a stroke is band-limited noise (200 Hz to 4 kHz) with a 5 ms
attack and a 50 ms release.  Each touch is heard on its channels with a gain drawn
between 0.5 and 1, and everything is reproducible from ``seed``.  The true touches come
back with the recording, so that event detection can be tested against them.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from touchbench.drivers.errors import DriverError
from touchbench.drivers.recording import Recording

TouchKind = Literal["tap", "stroke"]


@dataclass(frozen=True)
class SimulatedTouch:
    """One touch to synthesise.

    Parameters
    ----------
    onset : float
        Start in seconds.
    duration : float
        Length in seconds (a tap decays to 1 % of its amplitude by then).
    channels : tuple of int
        0-based channels that hear it.
    kind : {"tap", "stroke"}
    amplitude : float
        Peak amplitude at full gain (full scale is 1).
    """

    onset: float
    duration: float
    channels: tuple[int, ...]
    kind: TouchKind = "tap"
    amplitude: float = 0.3

    @property
    def end(self) -> float:
        return self.onset + self.duration


@dataclass(frozen=True)
class SimulatedSession:
    """A synthetic recording and the touches it contains, in time order."""

    recording: Recording
    touches: tuple[SimulatedTouch, ...]


def simulate_session(
    *,
    duration: float = 10.0,
    samplerate: float = 44100.0,
    n_channels: int = 3,
    touches: Sequence[SimulatedTouch] | None = None,
    n_touches: int = 5,
    min_gap: float = 1.0,
    noise_level: float = 1e-3,
    seed: int = 0,
) -> SimulatedSession:
    """Synthesise a touch session.

    Parameters
    ----------
    duration : float
        Seconds.
    samplerate : float
        Hz.
    n_channels : int
        Channels (microphones).
    touches : sequence of SimulatedTouch, optional
        The touches to place; by default ``n_touches`` random ones, taps of 20 to 100 ms
        and strokes of 0.3 to 1 s on random channels, separated by at least ``min_gap``
        seconds of quiet and starting after 0.5 s.
    n_touches : int
        Random touches when ``touches`` is not given.
    min_gap : float
        Quiet seconds between random touches.
    noise_level : float
        Standard deviation of the white noise floor.
    seed : int
        Seed of every random draw.

    Returns
    -------
    SimulatedSession
    """
    if duration <= 0 or samplerate <= 0 or n_channels < 1 or noise_level < 0:
        raise DriverError(
            "a simulated session needs a positive duration and sample rate, at least one "
            f"channel and a noise level of at least 0; got duration={duration}, "
            f"samplerate={samplerate}, n_channels={n_channels}, noise_level={noise_level}"
        )
    rng = np.random.default_rng(seed)
    n_samples = round(duration * samplerate)
    if touches is None:
        touches = _random_touches(rng, duration, n_channels, n_touches, min_gap)
    samples = noise_level * rng.standard_normal((n_channels, n_samples))
    for touch in touches:
        _check_touch(touch, duration, n_channels)
        start = round(touch.onset * samplerate)
        length = min(round(touch.duration * samplerate), n_samples - start)
        wave = _waveform(rng, touch, length, samplerate)
        for channel in touch.channels:
            samples[channel, start : start + length] += rng.uniform(0.5, 1.0) * wave
    recording = Recording(
        samples=samples, samplerate=float(samplerate), path=f"simulated(seed={seed})"
    )
    return SimulatedSession(
        recording=recording, touches=tuple(sorted(touches, key=lambda t: t.onset))
    )


def _check_touch(touch: SimulatedTouch, duration: float, n_channels: int) -> None:
    if not 0 <= touch.onset < duration or touch.duration <= 0 or not touch.channels:
        raise DriverError(
            f"touch at {touch.onset} s lasting {touch.duration} s on channels "
            f"{touch.channels} does not fit a {duration} s session"
        )
    if min(touch.channels) < 0 or max(touch.channels) >= n_channels:
        raise DriverError(
            f"touch at {touch.onset} s names channels {touch.channels}, but the session "
            f"has {n_channels}"
        )


def _random_touches(
    rng: np.random.Generator, duration: float, n_channels: int, count: int, min_gap: float
) -> list[SimulatedTouch]:
    touches = []
    time = 0.5
    for _ in range(count):
        kind: TouchKind = "tap" if rng.random() < 0.5 else "stroke"
        length = rng.uniform(0.02, 0.1) if kind == "tap" else rng.uniform(0.3, 1.0)
        onset = time + rng.uniform(0.0, 0.5)
        if onset + length >= duration:
            break
        size = int(rng.integers(1, n_channels + 1))
        channels = tuple(sorted(int(c) for c in rng.choice(n_channels, size, replace=False)))
        amplitude = float(rng.uniform(0.05, 0.5))
        touches.append(SimulatedTouch(onset, length, channels, kind, amplitude))
        time = onset + length + min_gap
    return touches


def _waveform(
    rng: np.random.Generator, touch: SimulatedTouch, length: int, samplerate: float
) -> np.ndarray:
    t = np.arange(length) / samplerate
    if touch.kind == "tap":
        decay = np.exp(-t * (np.log(100.0) / touch.duration))
        frequencies = rng.uniform(300.0, 3000.0, size=2)
        phases = rng.uniform(0, 2 * np.pi, size=2)
        ring = np.sin(2 * np.pi * frequencies[:, np.newaxis] * t + phases[:, np.newaxis])
        return touch.amplitude * decay * (0.7 * ring[0] + 0.3 * ring[1])
    spectrum = np.fft.rfft(rng.standard_normal(length))
    bins = np.fft.rfftfreq(length, 1.0 / samplerate)
    spectrum[(bins < 200.0) | (bins > 4000.0)] = 0
    noise = np.fft.irfft(spectrum, n=length)
    noise /= max(float(np.abs(noise).max()), 1e-12)
    return touch.amplitude * _attack_release(length, samplerate) * noise


def _attack_release(length: int, samplerate: float) -> np.ndarray:
    """Envelope of a stroke: 5 ms raised-cosine attack, sustain, 50 ms release."""
    attack = min(length, max(1, int(0.005 * samplerate)))
    release = min(length - attack, int(0.05 * samplerate))
    envelope = np.ones(length)
    envelope[:attack] = 0.5 - 0.5 * np.cos(np.pi * np.arange(attack) / attack)
    if release:
        envelope[length - release :] = 0.5 + 0.5 * np.cos(np.pi * np.arange(release) / release)
    return envelope
