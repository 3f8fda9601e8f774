"""MP3 audio that arrives in pieces (ROS audio messages), decoded block by block.

audio_capture publishes MP3 by default (``format: mp3``): each ``AudioData`` message
carries the next bytes of one MP3 stream, without the Xing/Info header a file has.
libsndfile (1.1 and later, through mpg123) decodes it from a file-like
:class:`ChunkStream` that reads the messages as it goes, so memory holds one window of
bytes and one block of samples, whatever the length of the bag.

Why the stream reports a length of 0: without a Xing/Info header, libsndfile takes the
number of frames from mpg123's *estimate* from the file's length and the first frame's
bitrate, and reads no further than that (a variable-bitrate stream was cut to a fifth in
our tests).  For a length it cannot use, libsndfile asks mpg123 to scan the stream for
the exact count instead; the scan reads the messages once more (headers only), and the
stream then rewinds by reading them again from the start.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator

import numpy as np
import soundfile

from touchbench.drivers.errors import DriverError

#: Bytes of the stream kept behind the read position, for libsndfile's short seeks back.
WINDOW = 1 << 20
#: The length an unbounded (live) stream reports: beyond any stream's end.
UNBOUNDED = 1 << 50

#: Kilobits per second by (MPEG-1?, layer) and bitrate index (0: free format, unused here).
_BITRATES = {
    (True, 1): (0, 32, 64, 96, 128, 160, 192, 224, 256, 288, 320, 352, 384, 416, 448),
    (True, 2): (0, 32, 48, 56, 64, 80, 96, 112, 128, 160, 192, 224, 256, 320, 384),
    (True, 3): (0, 32, 40, 48, 56, 64, 80, 96, 112, 128, 160, 192, 224, 256, 320),
    (False, 1): (0, 32, 48, 56, 64, 80, 96, 112, 128, 144, 160, 176, 192, 224, 256),
    (False, 2): (0, 8, 16, 24, 32, 40, 48, 56, 64, 80, 96, 112, 128, 144, 160),
    (False, 3): (0, 8, 16, 24, 32, 40, 48, 56, 64, 80, 96, 112, 128, 144, 160),
}
#: Sample rates by the header's version bits (0: MPEG 2.5, 2: MPEG 2, 3: MPEG 1).
_RATES = {0: (11025, 12000, 8000), 2: (22050, 24000, 16000), 3: (44100, 48000, 32000)}


class ChunkStream:
    """A read-only, seekable file over the bytes of ``open_chunks()``, read as needed.

    Parameters
    ----------
    open_chunks : callable
        Returns a new iterator over the stream's consecutive byte chunks (from the
        start) each time it is called.
    window : int
        Bytes kept behind the read position; a seek further back starts the chunks over.
    unbounded : bool
        A live stream (ROS messages as they come), which has no end to count the frames
        up to and cannot be read again: see Notes.

    Notes
    -----
    ``seek(0, SEEK_END)`` then ``tell()`` gives 0: the length is not known without
    reading everything, and libsndfile, for a length of 0, counts the frames exactly
    (see the module docstring).  That count would wait for the end of a live stream, so
    an unbounded stream reports :data:`UNBOUNDED` bytes instead (mpg123 then estimates
    more frames than any stream has and reads on as they come), and reads near that
    far end (mpg123 looking for an ID3v1 tag) give zeros (no tag).
    """

    def __init__(
        self,
        open_chunks: Callable[[], Iterator[bytes]],
        *,
        window: int = WINDOW,
        unbounded: bool = False,
    ):
        self._open = open_chunks
        self._window = window
        self._unbounded = unbounded
        self._restart()
        self.restarts = 0  # how often the chunks were read from the start again

    def _restart(self) -> None:
        self._chunks: Iterator[bytes] | None = self._open()
        self._buffer = bytearray()
        self._buffer_start = 0  # stream offset of self._buffer[0]
        self._position = 0
        self._at_end = False  # after seek(.., SEEK_END): reads give nothing, tell() 0

    def read(self, size: int = -1) -> bytes:
        if self._at_end:
            return b""
        if self._unbounded and self._position >= UNBOUNDED // 2:
            size = max(0, min(size, UNBOUNDED - self._position))
            self._position += size
            return bytes(size)
        if self._position < self._buffer_start:
            if self._unbounded:
                raise DriverError("cannot read a live MP3 stream again from its start")
            position = self._position
            self._restart()
            self.restarts += 1
            self._position = position
        wanted = self._position + (size if size >= 0 else 1 << 62)
        while self._buffer_start + len(self._buffer) < wanted and self._chunks is not None:
            chunk = next(self._chunks, None)
            if chunk is None:
                self._chunks = None
                break
            self._buffer += chunk
            self._trim()
        begin = self._position - self._buffer_start
        data = bytes(self._buffer[begin : begin + max(0, wanted - self._position)])
        self._position += len(data)
        self._trim()
        return data

    def _trim(self) -> None:
        # Never more than the buffer holds: after a seek forward, it may all be behind.
        excess = min(self._position - self._window - self._buffer_start, len(self._buffer))
        if excess > 0:
            del self._buffer[:excess]
            self._buffer_start += excess

    def seek(self, offset: int, whence: int = os.SEEK_SET) -> int:
        if whence == os.SEEK_END and self._unbounded:
            self._position = max(0, UNBOUNDED + offset)
            return self._position
        if whence == os.SEEK_END:
            self._at_end = True
            return 0
        base = self._position if whence == os.SEEK_CUR and not self._at_end else 0
        self._at_end = False
        self._position = max(0, base + offset)
        return self._position

    def tell(self) -> int:
        return 0 if self._at_end else self._position


class _ForwardFile(soundfile.SoundFile):
    """A sound file read forwards only.

    soundfile seeks to where it expects to be after every read from a seekable file; in
    variable-bitrate MP3 mpg123's seek is approximate, and that seek skipped or repeated
    audio (errors of 0.5 full scale in our tests).  A stream is read once, front to back.
    """

    def seekable(self) -> bool:
        return False


class Mp3Decoder:
    """The audio of an MP3 stream given as chunks, block by block.

    Parameters
    ----------
    open_chunks : callable
        As for :class:`ChunkStream`.
    name : str
        What the stream is, for messages.
    unbounded : bool
        A live stream, decoded as its chunks come (see :class:`ChunkStream`).

    Attributes
    ----------
    samplerate : float
    n_channels : int

    Raises
    ------
    DriverError
        libsndfile cannot read the bytes as MPEG audio.
    """

    def __init__(
        self, open_chunks: Callable[[], Iterator[bytes]], *, name: str, unbounded: bool = False
    ) -> None:
        self.name = name
        self.stream = ChunkStream(open_chunks, unbounded=unbounded)
        try:
            self._file = _ForwardFile(self.stream)
        except (soundfile.LibsndfileError, RuntimeError, TypeError) as error:
            raise DriverError(f"{name}: cannot decode as MP3: {error}") from None
        if self._file.format != "MP3":
            self._file.close()
            raise DriverError(f"{name}: holds {self._file.format} audio, not MP3")
        self.samplerate = float(self._file.samplerate)
        self.n_channels = int(self._file.channels)

    def blocks(self, length: int = 65536) -> Iterator[np.ndarray]:
        """Decoded samples, shape (n_channels, <= length) each, float64, full scale."""
        try:
            while (chunk := self._file.read(length, dtype="float64", always_2d=True)).size:
                yield np.ascontiguousarray(chunk.T)
        except (soundfile.LibsndfileError, RuntimeError) as error:
            raise DriverError(f"{self.name}: cannot decode the MP3 audio: {error}") from None

    def close(self) -> None:
        self._file.close()


def looks_like_mp3(data: bytes) -> bool:
    """True when ``data`` starts an MPEG audio stream: an ID3v2 tag, or a frame header
    followed by another one where the first frame ends (raw PCM seldom does both)."""
    if data[:3] == b"ID3":
        return True
    length = frame_length(data[:4])
    if length is None:
        return False
    if len(data) < length + 4:
        return len(data) >= 4  # one whole message of less than a frame: take the header
    return frame_length(data[length : length + 4]) is not None


def frame_length(header: bytes) -> int | None:
    """Bytes of the MPEG audio frame whose 4-byte ``header`` is given; None if not one."""
    if len(header) < 4 or header[0] != 0xFF or header[1] & 0xE0 != 0xE0:
        return None
    version, layer_bits = (header[1] >> 3) & 3, (header[1] >> 1) & 3
    bitrate_index, rate_index = header[2] >> 4, (header[2] >> 2) & 3
    if version == 1 or layer_bits == 0 or bitrate_index in (0, 15) or rate_index == 3:
        return None
    layer, mpeg1, padding = 4 - layer_bits, version == 3, (header[2] >> 1) & 1
    bitrate = _BITRATES[(mpeg1, layer)][bitrate_index] * 1000
    rate = _RATES[version][rate_index]
    if layer == 1:
        return (12 * bitrate // rate + padding) * 4
    return (144 if layer == 2 or mpeg1 else 72) * bitrate // rate + padding
