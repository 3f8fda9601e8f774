"""A second simulated sensor: active oscillation for contact localisation.

An eccentric-mass motor at about 170 Hz shakes a rigid link clamped at the motor's end;
a 3-axis accelerometer on the link samples at 3200 Hz (x and y across the link, z, the
last channel, vertical).  The link's first three bending modes (about 62, 522 and
862 Hz) ring under the motor's broadband bearing noise.  A contact at one of five
points along the link (10 % to 90 % of its length) adds stiffness and damping to each
mode in proportion to the square of its mode shape there (cantilever shapes
``sin((2k + 1) pi x / 2)``), which raises its frequency, widens its peak and changes
how much of the vibration is vertical; no contact leaves the free link.

Every trial differs (seeded): the motor's speed (1 %), the modes' frequencies (0.5 %,
as temperature does), the contact's force (a stiffness between 0.5 and 1.5 times the
nominal), the excitation's level and the sensor noise.  So the classes overlap: a
classifier learns the shifts, but cannot separate every trial.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from touchbench.drivers.errors import DriverError
from touchbench.drivers.recording import Recording

# Imports inside functions: start-up time: the service names the simulated sources among its
# live sources, and scipy.signal, the largest import of a service's start, would load unused

SAMPLERATE = 3200.0
MOTOR_HZ = 170.0
#: Contact positions along the link, as fractions of its length from the motor.
POSITIONS = (0.1, 0.3, 0.5, 0.7, 0.9)
#: Label of each contact class: no contact, then the five points.
CONTACTS = ("none", "p1", "p2", "p3", "p4", "p5")
#: Free-link modes: (frequency Hz, damping ratio, stiffness gain of a contact, x/y/z share).
_MODES = (
    (62.0, 0.030, 1.00, (0.25, 0.85, 0.45)),
    (522.0, 0.010, 0.09, (0.30, 0.25, 0.92)),
    (862.0, 0.008, 0.10, (0.55, 0.20, 0.80)),
)


@dataclass(frozen=True)
class LinkTrial:
    """One simulated trial: the recording (3, n) and its contact class."""

    recording: Recording
    contact: str


def simulate_link_trial(contact: str, *, duration: float = 3.0, seed: int = 0) -> LinkTrial:
    """One trial of the oscillating link with ``contact`` (a name of :data:`CONTACTS`).

    Parameters
    ----------
    contact : str
        ``none`` or ``p1`` ... ``p5``.
    duration : float
        Seconds.
    seed : int
        Seed of every random draw of the trial.

    Returns
    -------
    LinkTrial
        Samples in units of g, shape (3, duration * 3200).
    """
    if contact not in CONTACTS:
        raise DriverError(f"contact must be one of {', '.join(CONTACTS)}, got '{contact}'")
    if duration <= 0:
        raise DriverError(f"duration must be positive, got {duration}")
    rng = np.random.default_rng(seed)
    n = round(duration * SAMPLERATE)
    t = np.arange(n) / SAMPLERATE
    force = rng.uniform(0.5, 1.5)
    where = None if contact == "none" else POSITIONS[CONTACTS.index(contact) - 1]
    motor = MOTOR_HZ * (1 + rng.normal(0, 0.01))
    phase = 2 * np.pi * motor * t + 0.002 * np.cumsum(rng.standard_normal(n))  # speed wander
    excitation = rng.uniform(0.6, 1.4) * rng.standard_normal(n)
    samples = np.zeros((3, n))
    for k, (frequency, damping, gain, share) in enumerate(_MODES):
        frequency *= 1 + rng.normal(0, 0.005)
        if where is not None:
            shape = np.sin((2 * k + 1) * np.pi * where / 2) ** 2
            frequency *= np.sqrt(1 + force * gain * shape)
            damping += 0.012 * force * shape
            share = (share[0], share[1], share[2] * (1 - 0.3 * force * shape))
        samples += np.outer(share, _resonate(excitation, frequency, damping))
    unbalance = 0.8 * np.stack([np.cos(phase), np.sin(phase), 0.1 * np.cos(2 * phase)])
    samples += unbalance + 0.05 * rng.standard_normal((3, n))
    samples[2] += 1.0  # gravity on the vertical axis
    recording = Recording(samples=samples, samplerate=SAMPLERATE, path=f"link({contact}, {seed})")
    return LinkTrial(recording=recording, contact=contact)


def _resonate(x: np.ndarray, frequency: float, damping: float) -> np.ndarray:
    """``x`` through a two-pole resonator at ``frequency`` Hz with ``damping`` ratio."""
    from scipy.signal import lfilter

    radius = np.exp(-2 * np.pi * frequency * damping / SAMPLERATE)
    angle = 2 * np.pi * frequency / SAMPLERATE
    return np.asarray(
        lfilter([1 - radius], [1.0, -2 * radius * np.cos(angle), radius**2], x), np.float64
    )
