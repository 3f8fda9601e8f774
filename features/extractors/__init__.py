"""The registry of extractors: ``--extractor NAME`` to the class that implements it.

Each entry is an :class:`~features.extractors.base.Extractor` subclass carrying its
name, description, options, default event kind and sample-rate rules;
:func:`make_extractor` builds one with options.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from touchbench.features.errors import FeatureError
from touchbench.features.extractors.band_peaks import BandPeaks
from touchbench.features.extractors.base import Extractor, Instances
from touchbench.features.extractors.mfcc import Mfcc
from touchbench.features.extractors.sequence import Sequence
from touchbench.features.extractors.taxel_dft import TaxelDft
from touchbench.features.extractors.uc3m_audio import Uc3mAudio, uc3m_feature_names
from touchbench.features.extractors.window import Window

EXTRACTORS: dict[str, type[Extractor]] = {
    extractor.name: extractor
    for extractor in (Uc3mAudio, BandPeaks, Mfcc, TaxelDft, Window, Sequence)
}


def make_extractor(
    name: str, options: Mapping[str, Any] | None = None, *, samplerate: float | None = None
) -> Extractor:
    """The extractor called ``name`` with ``options``; with ``samplerate``, the defaults
    that depend on the sample rate are filled in (for the extractor's own event kind).

    Raises
    ------
    FeatureError
        For an unknown name or option.
    """
    if name not in EXTRACTORS:
        raise FeatureError(f"unknown extractor '{name}' (known: {', '.join(EXTRACTORS)})")
    kind = EXTRACTORS[name]
    extractor = kind(**dict(options or {}))
    if samplerate is None:
        return extractor
    filled, _ = kind.fill_defaults(
        extractor.params, samplerate=samplerate, events=kind.default_events, segment=None
    )
    return kind(**{key: value for key, value in filled.items() if value is not None})


__all__ = ["EXTRACTORS", "Extractor", "Instances", "make_extractor", "uc3m_feature_names"]
