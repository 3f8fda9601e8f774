"""Numeric fields of any topic of a ROS bag as channels: tactile arrays, BioTac, forces.

A field is named by its path in the message, as the bag's own message definition gives
it: ``pdc``, ``pac``, ``wrench.force.x``, ``sensors[0].values``.  A numeric field is one
channel; an array of numbers one channel per element (``pac[0]``, ``pac[1]``, ...); a
message field every numeric field inside it.  Without fields, a topic gives its
top-level numeric fields (``data`` of a ``std_msgs/Float32MultiArray``), or, when it has
none, the numeric fields inside its message fields (all but the header).

Every message is one sample of every channel, at the topic's own stamp: its
``header.stamp`` when it has one (and it is set), else the time the bag received it.
Stamps jitter, so the samples are put on an even grid (:mod:`drivers.resample`) at the
given rate or the stamps' median rate, with a note on the jitter.  Messages whose stamp
does not rise past the one before are left out (counted in a note).  The bag is read
twice, first for the stamps, then for the values, so memory holds the stamps (8 bytes a
message) and one block of messages.
"""

from __future__ import annotations

import re
from array import array
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from touchbench.drivers.bag_reader import close_bag, field_specs, raw_messages, reason
from touchbench.drivers.errors import DriverError
from touchbench.drivers.limits import ReadLimits
from touchbench.drivers.resample import EvenResampler, check_grid, jitter_note, median_rate
from touchbench.drivers.source import Block, Source

#: ROS base types read as numbers.
NUMERIC = frozenset(
    {
        "bool", "byte", "char", "int8", "uint8", "int16", "uint16", "int32", "uint32",
        "int64", "uint64", "float32", "float64",
    }
)  # fmt: skip
#: Messages per block of the second pass.
BATCH = 1024
_STEP = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)(?:\[(\d+)\])?$")


@dataclass(frozen=True)
class Leaf:
    """One numeric field to read: where it is in a message and what its channels are called.

    ``steps`` are attribute names and indices from the message down; ``array`` is true for
    an array of numbers (one channel per element).
    """

    label: str
    steps: tuple[str | int, ...]
    array: bool

    def values(self, message: Any) -> np.ndarray:
        """This field's values in ``message``, shape (n,), float64."""
        value = message
        for step in self.steps:
            value = value[step] if isinstance(step, int) else getattr(value, step)
        return np.asarray(value, dtype=np.float64).reshape(-1)


def plan_fields(
    reader: Any, msgtype: str, fields: Sequence[str] | None, *, where: str
) -> list[Leaf]:
    """The numeric leaves ``fields`` name in ``msgtype`` (or its default fields).

    Raises
    ------
    DriverError
        A field the type does not have, one that is not numeric, or no numeric field.
    """
    if fields:
        leaves = [leaf for text in fields for leaf in _resolve(reader, msgtype, text, where)]
    else:
        specs = field_specs(reader, msgtype)
        top = [(n, s) for n, s in specs if _numeric_leaf(s) is not None]
        nested = [(n, s) for n, s in specs if s[0].name == "NAME" and n != "header"]
        leaves = [leaf for n, s in (top or nested) for leaf in _leaves(reader, s, n, (n,))]
    if not leaves:
        raise DriverError(
            f"{where} ({msgtype}) has no numeric field; its fields: {_describe(reader, msgtype)}"
        )
    return leaves


def _resolve(reader: Any, msgtype: str, text: str, where: str) -> list[Leaf]:
    steps: list[str | int] = []
    spec: Any = None
    current = msgtype
    for part in text.strip().split("."):
        match = _STEP.match(part)
        if match is None:
            raise DriverError(f"{where}: field '{text}' is not a field path like a.b[2].c")
        name, index = match.group(1), match.group(2)
        specs = dict(field_specs(reader, current)) if current else {}
        if name not in specs:
            raise DriverError(
                f"{where}: {current or 'a number'} has no field '{name}' (in '{text}'); "
                f"its fields: {_describe(reader, current) if current else 'none'}"
            )
        spec = specs[name]
        steps.append(name)
        if index is not None:
            if spec[0].name not in ("ARRAY", "SEQUENCE"):
                raise DriverError(f"{where}: field '{name}' (in '{text}') is not an array")
            spec = spec[1][0]
            steps.append(int(index))
        current = spec[1] if spec[0].name == "NAME" else ""
    leaves = _leaves(reader, spec, text.strip(), tuple(steps))
    if not leaves:
        raise DriverError(
            f"{where}: field '{text}' is {_type_name(spec)}, not a number or an array of numbers"
        )
    return leaves


def _leaves(reader: Any, spec: Any, label: str, steps: tuple[str | int, ...]) -> list[Leaf]:
    """The numeric leaves of a field: itself, or those inside a message (not sequences
    of messages, whose length varies: name one element with an index)."""
    kind = _numeric_leaf(spec)
    if kind is not None:
        return [Leaf(label, steps, kind == "array")]
    if spec[0].name != "NAME":
        return []
    return [
        leaf
        for name, inner in field_specs(reader, spec[1])
        for leaf in _leaves(reader, inner, f"{label}.{name}", (*steps, name))
    ]


def _numeric_leaf(spec: Any) -> str | None:
    """``scalar`` or ``array`` for a number or an array of numbers; None otherwise."""
    kind, details = spec
    if kind.name == "BASE":
        return "scalar" if details[0] in NUMERIC else None
    if kind.name in ("ARRAY", "SEQUENCE"):
        inner = details[0]
        return "array" if inner[0].name == "BASE" and inner[1][0] in NUMERIC else None
    return None


def _type_name(spec: Any) -> str:
    kind, details = spec
    if kind.name == "BASE":
        return str(details[0])
    if kind.name == "NAME":
        return str(details)
    return f"an array of {_type_name(details[0])}"


def _describe(reader: Any, msgtype: str) -> str:
    specs = field_specs(reader, msgtype)
    return ", ".join(f"{name} ({_type_name(spec)})" for name, spec in specs) or "none"


class BagFieldsSource(Source):
    """Numeric fields of one topic of a ROS bag, on an even grid, block by block.

    Made by :func:`drivers.bags.open_bag_source`, which gives it the open bag (it closes
    it).

    Parameters
    ----------
    reader : rosbags AnyReader
        The open bag.
    connection : rosbags Connection
        The topic.
    name : str
        The bag, for messages.
    fields : sequence of str, optional
        Field paths (see the module docstring); the default fields otherwise.
    samplerate : float, optional
        The grid's rate; the stamps' median rate otherwise.

    Attributes
    ----------
    channel_names : list of str
        ``pdc``, ``pac[0]``, ... one per channel.
    start_time : float
        Seconds from the bag's first message to the first sample.
    notes : list of str
        The stamps used, their jitter and what was left out.
    """

    def __init__(
        self,
        reader: Any,
        connection: Any,
        *,
        name: str,
        fields: Sequence[str] | None = None,
        samplerate: float | None = None,
        limits: ReadLimits | None = None,
    ) -> None:
        self._reader = reader
        self._connection = connection
        self.name = name
        self.notes: list[str] = []
        where = f"{name}: topic '{connection.topic}'"
        try:
            self._leaves = plan_fields(reader, connection.msgtype, fields, where=where)
            header = dict(field_specs(reader, connection.msgtype)).get("header")
            self._header = header is not None and "stamp" in dict(
                field_specs(reader, header[1]) if header[0].name == "NAME" else []
            )
            times, self._keep, first = self._stamps()
            self.channel_names = [
                f"{leaf.label}[{i}]" if leaf.array else leaf.label
                for leaf in self._leaves
                for i in range(leaf.values(first).size)
            ]
            self.n_channels = len(self.channel_names)
            self.samplerate = float(samplerate) if samplerate else median_rate(times)
            self.resampled = not samplerate
            self.start_time = float(times[0])
            self._times = times
            numbers = np.flatnonzero(self._keep) + 1
            check_grid(
                times,
                self.samplerate,
                self.n_channels,
                limits or ReadLimits(),
                at=lambda i: f"{where}: message {numbers[i]}'s stamp jumps",
                before="the message before",
            )
            note = jitter_note(times, self.samplerate, what=f"stamps of '{connection.topic}'")
            self.notes += [note] if note else []
        except BaseException:
            self.close()
            raise

    def _messages(self, *, wanted: bool = True) -> Iterator[tuple[int, int, Any]]:
        """``(number from 1, receive time ns, message)`` of the topic, in order; the
        message is None when not ``wanted`` (only the receive times are read then)."""
        connection = self._connection
        for number, (stamp, raw) in enumerate(
            raw_messages(self._reader, connection, name=self.name), 1
        ):
            if not wanted and number > 1:
                yield number, stamp, None
                continue
            try:
                message = self._reader.deserialize(raw, connection.msgtype)
            except Exception as error:
                raise DriverError(
                    f"{self.name}: message {number} on '{connection.topic}' cannot be "
                    f"read: {reason(error)}"
                ) from None
            yield number, stamp, message

    def _stamps(self) -> tuple[np.ndarray, np.ndarray, Any]:
        """Pass one: seconds from the bag's start of the kept messages, which messages are
        kept, and the first message."""
        # 8 bytes a message (a list of ints takes several times that).
        received, stamped = array("q"), array("q")
        first: Any = None
        for _, stamp, message in self._messages(wanted=self._header):
            received.append(stamp)
            if self._header:
                header_stamp = message.header.stamp
                stamped.append(int(header_stamp.sec) * 10**9 + int(header_stamp.nanosec))
            if first is None:
                self._values(message, 1)  # a field the message lacks is refused here
                first = message
        topic = self._connection.topic
        if first is None:
            raise DriverError(f"{self.name}: topic '{topic}' has no messages")
        stamps = np.frombuffer(received, dtype=np.int64)
        if self._header and min(stamped) > 0:
            stamps = np.frombuffer(stamped, dtype=np.int64)
        elif self._header:
            self.notes.append(
                f"'{topic}' read at the times the bag received it: its header stamps are not set"
            )
        # Stamps that do not rise past the last kept one cannot be put on a grid in order.
        keep = np.ones(stamps.size, dtype=bool)
        keep[1:] = stamps[1:] > np.maximum.accumulate(stamps)[:-1]
        if not keep.all():
            self.notes.append(
                f"{int((~keep).sum())} message(s) of '{topic}' whose stamp did not rise past "
                "the one before were left out"
            )
        times = (stamps[keep] - self._reader.start_time) / 1e9
        if times.size < 2:
            raise DriverError(
                f"{self.name}: topic '{topic}' has {times.size} message(s) with rising stamps; "
                "at least two are needed for a sample rate"
            )
        return times, keep, first

    def _values(self, message: Any, number: int) -> np.ndarray:
        try:
            parts = [leaf.values(message) for leaf in self._leaves]
        except (AttributeError, IndexError, TypeError, ValueError) as error:
            raise DriverError(
                f"{self.name}: message {number} on '{self._connection.topic}': {reason(error)}"
            ) from None
        return np.concatenate(parts)

    def blocks(self) -> Iterator[Block]:
        resampler = EvenResampler(self.start_time, self.samplerate)
        times: list[float] = []
        rows: list[np.ndarray] = []
        kept = 0

        def flush() -> Block | None:
            if not rows:
                return None
            first = resampler.produced
            out = resampler.feed(np.asarray(times), np.stack(rows, axis=1))
            times.clear()
            rows.clear()
            if out.shape[1] == 0:
                return None
            return Block(out, self.start_time + first / self.samplerate)

        for number, _, message in self._messages():
            if not self._keep[number - 1]:
                continue
            values = self._values(message, number)
            if values.size != self.n_channels:
                raise DriverError(
                    f"{self.name}: message {number} on '{self._connection.topic}' has "
                    f"{values.size} values, the first {self.n_channels}: the fields' "
                    "arrays must keep their length"
                )
            times.append(float(self._times[kept]))
            rows.append(values)
            kept += 1
            if len(rows) >= BATCH and (block := flush()) is not None:
                yield block
        if (block := flush()) is not None:
            yield block

    def close(self) -> None:
        close_bag(self._reader)
