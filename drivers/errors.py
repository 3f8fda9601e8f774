"""The drivers package's one error type.

A recording that cannot be read as it stands (missing, empty, unreadable, NaN samples,
no sample rate) is a :class:`DriverError`, raised with the file's name in its message;
errors of the libraries underneath are translated into it at this boundary.
"""

from __future__ import annotations


class DriverError(Exception):
    """A recording or a signal source that cannot be used."""
