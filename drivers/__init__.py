"""touchbench: drivers, the sources of signal samples.

``files``      read a recording (WAV/FLAC/..., CSV, ``.npy``) into a :class:`Recording`
``simulated``  synthetic touch sessions with known touches, for tests and benchmarks
``source``     the block :class:`~drivers.source.Source` protocol and a file replay

Every problem is a :class:`drivers.errors.DriverError`.
"""

from drivers.recording import Recording

__all__ = ["Recording"]
