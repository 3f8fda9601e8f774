"""An extraction recipe: extractor, event detector and their options, as JSON.

A data set extracted from recordings keeps its recipe, and so does every model trained
on it, so that live features are computed exactly as the training features were.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

from touchbench.features.errors import FeatureError
from touchbench.features.event_streams import DEFAULT_MAX_EVENT, open_event_stream
from touchbench.features.events import EVENT_KINDS
from touchbench.features.extractors import EXTRACTORS, Extractor, make_extractor
from touchbench.features.options import claim_options, resolve_options
from touchbench.features.stream import FeatureStream


@dataclass(frozen=True)
class Recipe:
    """How instances are made from samples.

    Parameters
    ----------
    extractor : str
        A key of :data:`features.extractors.EXTRACTORS`.
    events : str
        A key of :data:`features.events.EVENT_KINDS`.
    extractor_options, event_options : dict
        Every option, resolved (defaults filled in).
    segment : float or None
        Segment seconds for events ``none``.
    max_event : float
        Longest event in seconds; longer ones are cut, with a warning.
    """

    extractor: str
    events: str
    extractor_options: dict[str, Any] = field(default_factory=dict)
    event_options: dict[str, Any] = field(default_factory=dict)
    segment: float | None = None
    max_event: float = DEFAULT_MAX_EVENT

    @classmethod
    def resolve(
        cls,
        extractor: str,
        *,
        events: str | None = None,
        segment: float | None = None,
        options: Mapping[str, Any] | None = None,
        max_event: float | None = None,
    ) -> Recipe:
        """A recipe from what a user asks for: defaults of the extractor, options given in
        one flat mapping (each taken by the extractor or the detector that declares it).

        Raises
        ------
        FeatureError
            Unknown extractor, event kind or option; a bad option value.
        """
        if extractor not in EXTRACTORS:
            raise FeatureError(f"unknown extractor '{extractor}' (known: {', '.join(EXTRACTORS)})")
        spec = EXTRACTORS[extractor]
        kind = events or spec.default_events
        if kind not in EVENT_KINDS:
            raise FeatureError(
                f"unknown event detection '{kind}' (known: {', '.join(EVENT_KINDS)})"
            )
        mine, rest = claim_options(spec.options, options or {})
        detector, unknown = claim_options(EVENT_KINDS[kind].options, rest)
        if unknown:
            known = [o.name for o in (*spec.options, *EVENT_KINDS[kind].options)]
            raise FeatureError(
                f"unknown option '{sorted(unknown)[0]}' for extractor '{extractor}' with events "
                f"'{kind}' (options: {', '.join(known) if known else 'none'})"
            )
        if kind == "none" and segment is None:
            segment = spec.default_segment
        if segment is not None and kind != "none":
            raise FeatureError(f"a segment length only applies to events 'none', not '{kind}'")
        return cls(
            extractor=extractor,
            events=kind,
            extractor_options=dict(make_extractor(extractor, _given(mine)).params),
            event_options=resolve_options(
                EVENT_KINDS[kind].options, detector, owner=f"events '{kind}'"
            ),
            segment=segment,
            max_event=DEFAULT_MAX_EVENT if max_event is None else max_event,
        )

    def make_extractor(self) -> Extractor:
        return make_extractor(self.extractor, _given(self.extractor_options))

    def needs_longest(self) -> bool:
        """Whether :meth:`at_rate` needs the longest recording's length (a sequence of
        whole recordings)."""
        return EXTRACTORS[self.extractor].needs_longest(
            self.extractor_options, events=self.events, segment=self.segment
        )

    def at_rate(self, samplerate: float, *, longest: int | None = None) -> tuple[Recipe, list[str]]:
        """This recipe with the options that depend on the recordings filled in (defaults
        computed from the sample rate, a sequence's length from the longest recording),
        and a note for each; itself when nothing depends on them.

        Raises
        ------
        FeatureError
            A filled-in value the extractor refuses.
        """
        filled, notes = EXTRACTORS[self.extractor].fill_defaults(
            self.extractor_options,
            samplerate=samplerate,
            events=self.events,
            segment=self.segment,
            longest=longest,
        )
        if filled == self.extractor_options:
            return self, notes
        options = dict(make_extractor(self.extractor, _given(filled)).params)
        return replace(self, extractor_options=options), notes

    def open(
        self, *, samplerate: float, n_channels: int, channels: Sequence[str] | None = None
    ) -> FeatureStream:
        """A :class:`FeatureStream` for a stream of ``n_channels`` at ``samplerate`` Hz
        (with the defaults that depend on the rate filled in), its features named after
        ``channels`` if given."""
        recipe, _ = self.at_rate(samplerate)
        if recipe is not self:
            return recipe.open(samplerate=samplerate, n_channels=n_channels, channels=channels)
        events = open_event_stream(
            self.events,
            n_channels,
            samplerate=samplerate,
            segment=self.segment,
            options=self.event_options,
            max_event=self.max_event,
        )
        return FeatureStream(
            self.make_extractor(),
            events,
            samplerate=samplerate,
            n_channels=n_channels,
            channels=channels,
        )

    def to_json(self) -> dict[str, Any]:
        return {
            "extractor": self.extractor,
            "extractor_options": _plain(self.extractor_options),
            "events": self.events,
            "event_options": _plain(self.event_options),
            "segment": self.segment,
            "max_event": self.max_event,
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> Recipe:
        """The recipe :meth:`to_json` wrote (options parsed again, so checked)."""
        try:
            recipe = cls.resolve(
                str(data["extractor"]),
                events=str(data["events"]),
                segment=data.get("segment"),
                options=_given({**data["extractor_options"], **data["event_options"]}),
                max_event=data.get("max_event"),
            )
        except (KeyError, TypeError, AttributeError) as error:
            raise FeatureError(f"not an extraction recipe: {error!r}") from None
        return recipe


def _given(options: Mapping[str, Any]) -> dict[str, Any]:
    """Options without the unset ones (``None`` stands for the default)."""
    return {key: value for key, value in options.items() if value is not None}


def _plain(options: Mapping[str, Any]) -> dict[str, Any]:
    """Options as JSON values (tuples as lists)."""
    return {key: _list(value) for key, value in options.items()}


def _list(value: Any) -> Any:
    if isinstance(value, tuple | list):
        return [_list(item) for item in value]
    return value
