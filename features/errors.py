"""The features package's one error type.

Every problem with the signal or the parameters handed to a feature function (NaN
samples, a signal shorter than one window, an unusable sample rate, an unknown option)
is a :class:`FeatureError`; anything else raised from this package is a bug.
"""

from __future__ import annotations


class FeatureError(ValueError):
    """Bad input to a feature function, an extractor or an event detector."""
