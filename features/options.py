"""Named options of extractors and event detectors, parsed from Python values or CLI text.

Options arrive as a flat mapping (``{"threshold": "12", "bands": "0-120,500-550"}``):
each extractor and detector declares the options it owns with a parser and a default,
and :func:`claim_options` takes its own out of the mapping.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from touchbench.features.errors import FeatureError

Parser = Callable[[Any], Any]


@dataclass(frozen=True)
class Option:
    """One option: its name, default value, parser and a one-line description.

    Parameters
    ----------
    name : str
        The key (``-O name=value``).
    default : Any
        The value when none is given; ``None`` for "not set" (then ``default_text`` says
        what that means, and ``at_rate``, if set, computes it from the sample rate).
    parse : callable
        Text or a Python value to the option's value; ``ValueError`` for a bad one.
    help : str
        What the option means, one line.
    at_rate : callable, optional
        The default at a sample rate (Hz), for defaults that depend on it.
    default_text : str, optional
        The default in words, when it is computed (from the sample rate, the events...).
    """

    name: str
    default: Any
    parse: Parser
    help: str
    at_rate: Callable[[float], Any] | None = None
    default_text: str | None = None

    @property
    def kind(self) -> str:
        """The value's type in words (``integer >= 1``, ``boolean``...)."""
        return KINDS.get(self.parse, getattr(self.parse, "__name__", "value"))


def positive_float(value: Any) -> float:
    """A finite number greater than 0."""
    number = _float(value)
    if number <= 0:
        raise ValueError("must be greater than 0")
    return number


def non_negative_float(value: Any) -> float:
    """A finite number of at least 0."""
    number = _float(value)
    if number < 0:
        raise ValueError("must be at least 0")
    return number


def fraction(value: Any) -> float:
    """A number in (0, 1]."""
    number = _float(value)
    if not 0 < number <= 1:
        raise ValueError("must be in (0, 1]")
    return number


def positive_int(value: Any) -> int:
    """A whole number of at least 1 (``"25"`` and ``25.0`` accepted)."""
    number = _float(value)
    if number != int(number) or number < 1:
        raise ValueError("must be a whole number of at least 1")
    return int(number)


def non_negative_int(value: Any) -> int:
    """A whole number of at least 0."""
    number = _float(value)
    if number != int(number) or number < 0:
        raise ValueError("must be a whole number of at least 0")
    return int(number)


def flag(value: Any) -> bool:
    """A boolean; text ``true/false/yes/no/1/0``."""
    if isinstance(value, bool):
        return value
    text = str(value).strip().lower()
    if text in {"true", "yes", "1", "on"}:
        return True
    if text in {"false", "no", "0", "off"}:
        return False
    raise ValueError("must be true or false")


def frequency_bands(value: Any) -> tuple[tuple[float, float], ...]:
    """Bands in Hz: ``"0-120,500-550"`` or a sequence of ``(low, high)`` pairs."""
    if isinstance(value, str):
        pairs: list[Any] = [part.split("-") for part in value.split(",") if part.strip()]
    else:
        pairs = list(value)
    bands = []
    for pair in pairs:
        if len(pair) != 2:
            raise ValueError(f"each band must be LOW-HIGH, got {pair!r}")
        low, high = _float(pair[0]), _float(pair[1])
        if not 0 <= low < high:
            raise ValueError(f"band {low:g}-{high:g} must have 0 <= low < high")
        bands.append((low, high))
    if not bands:
        raise ValueError("needs at least one band")
    return tuple(bands)


#: The type of each parser in words, for listings.
KINDS: dict[Callable[[Any], Any], str] = {
    positive_float: "number > 0",
    non_negative_float: "number >= 0",
    fraction: "number in (0, 1]",
    positive_int: "integer >= 1",
    non_negative_int: "integer >= 0",
    flag: "boolean",
    frequency_bands: "bands LOW-HIGH,... (Hz)",
}


def _float(value: Any) -> float:
    if isinstance(value, bool):
        raise ValueError("must be a number")
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"must be a number, got {value!r}") from None
    if not math.isfinite(number):
        raise ValueError("must be finite")
    return number


def resolve_options(
    specs: tuple[Option, ...], given: Mapping[str, Any], *, owner: str
) -> dict[str, Any]:
    """Every option of ``specs``: the parsed given value, or the default.

    Raises
    ------
    FeatureError
        For a key ``specs`` does not declare, or a value its parser rejects.
    """
    known = {spec.name: spec for spec in specs}
    unknown = sorted(set(given) - set(known))
    if unknown:
        raise FeatureError(
            f"unknown option '{unknown[0]}' for {owner} "
            f"(options: {', '.join(known) if known else 'none'})"
        )
    resolved = {}
    for spec in specs:
        if given.get(spec.name) is None:
            resolved[spec.name] = spec.default
            continue
        try:
            resolved[spec.name] = spec.parse(given[spec.name])
        except ValueError as error:
            raise FeatureError(
                f"option '{spec.name}' of {owner}: {error} (got {given[spec.name]!r})"
            ) from None
    return resolved


def claim_options(
    specs: tuple[Option, ...], given: Mapping[str, Any]
) -> tuple[dict[str, Any], dict[str, Any]]:
    """Split ``given`` into the entries ``specs`` declares and the rest (both unparsed)."""
    names = {spec.name for spec in specs}
    mine = {key: value for key, value in given.items() if key in names}
    rest = {key: value for key, value in given.items() if key not in names}
    return mine, rest
