"""Dates in ARFF files: Java ``SimpleDateFormat`` patterns, parsed and written in UTC.

A date attribute stores seconds since the Unix epoch (UTC) as a float, as WEKA does in
milliseconds; :class:`DateFormat` turns the text of one value into those seconds and
back, for the pattern the attribute declares (WEKA's ISO-8601 default otherwise).
"""

from __future__ import annotations

import math
import re
from datetime import UTC, date, datetime

DEFAULT_DATE_FORMAT = "yyyy-MM-dd'T'HH:mm:ss"
_DATE_LETTERS = "yMdHmsSZX"
_MONTHS = (
    "January",
    "February",
    "March",
    "April",
    "May",
    "June",
    "July",
    "August",
    "September",
    "October",
    "November",
    "December",
)
_MONTH_NUMBERS = {
    **{name.lower(): i + 1 for i, name in enumerate(_MONTHS)},
    **{name[:3].lower(): i + 1 for i, name in enumerate(_MONTHS)},
}
_EPOCH_ORDINAL = date(1970, 1, 1).toordinal()
_DateElement = str | tuple[str, int]


class DateFormat:
    """A Java ``SimpleDateFormat`` pattern, parsed and formatted in UTC.

    Supported: the letters ``y M d H m s S`` (``MMM`` and ``MMMM`` for English month
    names; ``S`` counts milliseconds, as in Java), the zone letters ``Z`` and ``X``
    (any offset is read; UTC is written), text in single quotes (``''`` for a quote)
    and any other non-letter character as itself.  Numeric fields that abut another
    numeric field (``yyyyMMdd``) have exactly as many digits as letters.

    Parameters
    ----------
    pattern : str or None
        The pattern; ``None`` for WEKA's default ``yyyy-MM-dd'T'HH:mm:ss``.

    Raises
    ------
    ValueError
        If the pattern uses an unsupported letter or does not close a quote.
    """

    def __init__(self, pattern: str | None = None) -> None:
        self.pattern = DEFAULT_DATE_FORMAT if pattern is None else pattern
        self._elements = _date_elements(self.pattern)
        self._regex = re.compile(_date_regex(self._elements), re.IGNORECASE)

    def parse(self, text: str) -> float:
        """Seconds since the Unix epoch (UTC) of a date written in this format.

        Raises
        ------
        ValueError
            If ``text`` does not match the pattern or names an impossible date.
        """
        match = self._regex.fullmatch(text.strip())
        if match is None:
            raise ValueError(f"'{text}' does not match the date format '{self.pattern}'")
        fields = {"y": 1970, "M": 1, "d": 1, "H": 0, "m": 0, "s": 0, "S": 0}
        offset = 0
        for position, element in enumerate(self._elements):
            if isinstance(element, str):
                continue
            letter, count = element
            value = match.group(f"f{position}")
            if letter in "ZX":
                offset = _zone_offset(value)
            elif letter == "M" and count >= 3:
                month = _MONTH_NUMBERS.get(value.lower())
                if month is None:
                    raise ValueError(
                        f"'{text}' is not a valid date for the format '{self.pattern}': "
                        f"'{value}' is not a month name"
                    )
                fields["M"] = month
            elif letter == "y" and count == 2 and len(value) == 2:
                fields["y"] = _two_digit_year(int(value))
            else:
                fields[letter] = int(value)
        for letter, name, top in (
            ("H", "hour", 23),
            ("m", "minute", 59),
            ("s", "second", 59),
            ("S", "millisecond", 999),
        ):
            if fields[letter] > top:
                raise ValueError(
                    f"'{text}' is not a valid date for the format '{self.pattern}': "
                    f"{name} {fields[letter]} is out of range 0..{top}"
                )
        try:
            days = date(fields["y"], fields["M"], fields["d"]).toordinal() - _EPOCH_ORDINAL
        except ValueError as error:
            raise ValueError(
                f"'{text}' is not a valid date for the format '{self.pattern}': {error}"
            ) from None
        seconds = days * 86400 + fields["H"] * 3600 + fields["m"] * 60 + fields["s"] - offset
        return seconds + fields["S"] / 1000

    def format(self, seconds: float) -> str:
        """``seconds`` since the Unix epoch written in this format (UTC).

        Raises
        ------
        ValueError
            If the date falls outside the years 1 to 9999.
        """
        if not math.isfinite(seconds):
            raise ValueError(f"{seconds} seconds is not a date")
        whole, millisecond = divmod(round(seconds * 1000), 1000)
        days, rest = divmod(whole, 86400)
        try:
            day = date.fromordinal(_EPOCH_ORDINAL + days)
        except (ValueError, OverflowError):
            raise ValueError(f"{seconds} seconds is outside the years 1 to 9999") from None
        hour, rest = divmod(rest, 3600)
        minute, second = divmod(rest, 60)
        numbers = {"d": day.day, "H": hour, "m": minute, "s": second, "S": millisecond}
        parts = []
        for element in self._elements:
            if isinstance(element, str):
                parts.append(element)
                continue
            letter, count = element
            if letter == "y":
                parts.append(f"{day.year % 100:02d}" if count == 2 else f"{day.year:0{count}d}")
            elif letter == "M":
                if count >= 4:
                    parts.append(_MONTHS[day.month - 1])
                elif count == 3:
                    parts.append(_MONTHS[day.month - 1][:3])
                else:
                    parts.append(f"{day.month:0{count}d}")
            elif letter == "Z":
                parts.append("+0000")
            elif letter == "X":
                parts.append("Z")
            else:
                parts.append(f"{numbers[letter]:0{count}d}")
        return "".join(parts)


def _date_elements(pattern: str) -> list[_DateElement]:
    """Literal strings and (letter, count) fields of a SimpleDateFormat pattern."""
    elements: list[_DateElement] = []
    literal: list[str] = []
    i = 0
    while i < len(pattern):
        char = pattern[i]
        if char == "'":
            if pattern.startswith("''", i):
                literal.append("'")
                i += 2
                continue
            i += 1
            while True:
                if i >= len(pattern):
                    raise ValueError(f"date format '{pattern}' does not close a quote")
                if pattern.startswith("''", i):
                    literal.append("'")
                    i += 2
                elif pattern[i] == "'":
                    i += 1
                    break
                else:
                    literal.append(pattern[i])
                    i += 1
        elif char.isascii() and char.isalpha():
            if char not in _DATE_LETTERS:
                raise ValueError(
                    f"date format '{pattern}': the letter '{char}' is not supported "
                    "(supported: y M d H m s S Z X and 'quoted text')"
                )
            end = i
            while end < len(pattern) and pattern[end] == char:
                end += 1
            if literal:
                elements.append("".join(literal))
                literal = []
            elements.append((char, end - i))
            i = end
        else:
            literal.append(char)
            i += 1
    if literal:
        elements.append("".join(literal))
    return elements


def _is_numeric_field(element: _DateElement) -> bool:
    return (
        not isinstance(element, str)
        and element[0] not in "ZX"
        and not (element[0] == "M" and element[1] >= 3)
    )


def _date_regex(elements: list[_DateElement]) -> str:
    parts = []
    for position, element in enumerate(elements):
        if isinstance(element, str):
            parts.append(re.escape(element))
            continue
        letter, count = element
        group = f"(?P<f{position}>"
        if letter in "ZX":
            parts.append(group + r"Z|[+-]\d{2}(?::?\d{2})?)")
        elif letter == "M" and count >= 3:
            parts.append(group + "[A-Za-z]+)")
        else:
            abuts = position + 1 < len(elements) and _is_numeric_field(elements[position + 1])
            parts.append(group + (rf"\d{{{count}}})" if abuts else r"\d+)"))
    return "".join(parts)


def _zone_offset(text: str) -> int:
    """Seconds east of UTC of ``Z``, ``+hh``, ``+hhmm`` or ``+hh:mm``."""
    if text in ("Z", "z"):
        return 0
    digits = text[1:].replace(":", "")
    hours, minutes = int(digits[:2]), int(digits[2:] or 0)
    if hours > 23 or minutes > 59:
        raise ValueError(f"time zone offset '{text}' is out of range")
    return (hours * 3600 + minutes * 60) * (-1 if text[0] == "-" else 1)


def _two_digit_year(value: int) -> int:
    """Java's rule for ``yy``: the year within 80 years before and 20 after now."""
    start = datetime.now(UTC).year - 80
    year = start - start % 100 + value
    return year + 100 if year < start else year
