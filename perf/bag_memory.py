"""Memory of decoding MP3 ROS bags as they grow: touchbench's stream beside decoding whole.

Run from the repository root::

    .venv/bin/python perf/bag_memory.py [--minutes 1 4 16] [--storage bag]

Writes, for each length, a bag of audio_capture-style MP3 (2 channels, 44.1 kHz, variable
bitrate, no Xing header, 1000-byte ``audio_common_msgs/AudioData`` messages, no AudioInfo)
and reads it in a fresh process two ways:

* ``touchbench``: :class:`drivers.replay.FileReplaySource`, block by block (what
  ``extract`` does);
* ``whole``: the usual script: join every message's bytes, decode them at once with
  libsndfile (``soundfile.read``).

Prints each process's peak RSS (``VmHWM``), seconds of audio decoded per second, and
the peak over the first length's peak: flat for touchbench, growing with the length for
the whole decode; and the seconds of audio each decoded (libsndfile given the whole
stream stops at its estimate of a variable-bitrate stream's length without a Xing
header).  Not a test: nothing is asserted.
"""

from __future__ import annotations

import argparse
import io
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import soundfile

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

RATE = 44100


def child(path: str, how: str) -> None:
    """Read the bag ``how`` and print 'peak_kib seconds_of_audio elapsed'."""
    began = time.perf_counter()
    if how == "touchbench":
        from touchbench.drivers.replay import FileReplaySource

        n = 0
        with FileReplaySource(path) as source:
            for block in source.blocks():
                n += block.samples.shape[1]
    else:
        from rosbags.highlevel import AnyReader

        from touchbench.drivers.bag_reader import audio_typestore

        with AnyReader([Path(path)], default_typestore=audio_typestore()) as reader:
            data = b"".join(
                bytes(reader.deserialize(raw, connection.msgtype).data)
                for connection, _, raw in reader.messages()
                if connection.topic == "/audio/audio"
            )
        n = soundfile.read(io.BytesIO(data), dtype="float64")[0].shape[0]
    elapsed = time.perf_counter() - began
    print(peak_kib(), n / RATE, elapsed)


def peak_kib() -> int:
    """This process's peak resident memory, KiB: VmHWM, which (unlike ``ru_maxrss``, kept
    across ``exec`` from the parent) starts afresh with the program."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1])
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss


def write_bag(folder: Path, minutes: float, storage: str) -> Path:
    from tests.support.bagfiles import mp3_stream
from tests.support.bagfiles import pieces
from tests.support.bagfiles import write_audio_bag

    rng = np.random.default_rng(0)
    seconds = round(minutes * 60)
    # A tone and noise, a minute at a time, so that writing needs no more than a minute.
    t = np.arange(60 * RATE) / RATE
    minute = np.stack([0.3 * np.sin(2 * np.pi * 440 * t), rng.normal(0, 0.1, t.size)])
    stream = b"".join(
        mp3_stream(minute[:, : min(60, seconds - start) * RATE], RATE, variable=True)
        for start in range(0, seconds, 60)
    )
    return write_audio_bag(
        folder / f"mic-{minutes:g}min.{storage}",
        minute[:, :1],
        RATE,
        coding_format="mp3",
        payloads=pieces(stream, 1000),
        info_topic=None,
        extra_topic=False,
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, nargs="+", default=[1.0, 4.0, 16.0])
    parser.add_argument("--storage", choices=["bag", "mcap", "db3"], default="bag")
    parser.add_argument("--child", nargs=2, metavar=("PATH", "HOW"), help=argparse.SUPPRESS)
    arguments = parser.parse_args()
    if arguments.child:
        child(*arguments.child)
        return
    load = ", ".join(f"{value:.1f}" for value in os.getloadavg())
    print(f"Machine load average (1, 5, 15 min): {load} on {os.cpu_count()} cores")
    print(f"MP3 (VBR, 2 x 44.1 kHz) in a ROS {arguments.storage} bag, 1000-byte messages")
    print(f"{'minutes':>7} {'bag MiB':>8} {'reader':>10} {'peak MiB':>9} {'x first':>8} "
          f"{'decoded s':>10} {'audio s / s':>12}")  # fmt: skip
    first: dict[str, float] = {}
    with tempfile.TemporaryDirectory() as folder:
        for minutes in arguments.minutes:
            bag = write_bag(Path(folder), minutes, arguments.storage)
            size = sum(f.stat().st_size for f in ([bag] if bag.is_file() else bag.iterdir()))
            for how in ("touchbench", "whole"):
                output = subprocess.run(
                    [sys.executable, __file__, "--child", str(bag), how],
                    check=True,
                    capture_output=True,
                    text=True,
                ).stdout.split()
                peak, audio, elapsed = int(output[0]) / 1024, float(output[1]), float(output[2])
                first.setdefault(how, peak)
                print(
                    f"{minutes:>7g} {size / 2**20:>8.1f} {how:>10} {peak:>9.0f} "
                    f"{peak / first[how]:>8.2f} {audio:>10.1f} {audio / elapsed:>12.0f}"
                )


if __name__ == "__main__":
    main()
