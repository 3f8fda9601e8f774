"""Commands of the signal path: devices, record, simulate, live."""

from __future__ import annotations

import json

# Imports inside functions: start-up time. This module holds several commands and the
# one chosen loads only what it uses (the CLI imports the module when a command of it
# is chosen).
import sys
from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from touchbench.app.cli.extract import key_values
from touchbench.app.cli.output import EngineOption, JsonOption, info, print_json, table, warn
from touchbench.app.cli.state import get_state
from touchbench.app.errors import AppError
from touchbench.drivers.source import LIVE_BLOCK


def register(app: typer.Typer) -> None:
    app.command("devices")(devices_command)
    app.command("record")(record_command)
    app.command("simulate")(simulate_command)
    app.command("live")(live_command)


def devices_command(as_json: JsonOption = False) -> None:
    """List the capture devices PortAudio sees (index, name, input channels, default rate)."""
    from touchbench.drivers.sound import list_devices

    devices = list_devices()
    if as_json:
        print_json({"devices": [device.to_json() for device in devices]})
        return
    if not devices:
        info("PortAudio sees no capture device")
        return
    table(
        None,
        ["index", "name", "input channels", "default Hz", "host API"],
        [
            (d.index, d.name, d.input_channels, f"{d.default_samplerate:g}", d.hostapi)
            for d in devices
        ],
    )


def record_command(
    device: Annotated[
        str, typer.Option("--device", "-d", metavar="DEV", help="Device index or name.")
    ],
    out: Annotated[
        Path, typer.Option("--out", "-o", metavar="DIR", help="Session folder (created).")
    ],
    channels: Annotated[
        int | None,
        typer.Option("--channels", min=1, metavar="N", help="Channels (default: all)."),
    ] = None,
    samplerate: Annotated[
        float | None,
        typer.Option("--samplerate", metavar="HZ", help="Hz (default: the device's)."),
    ] = None,
    seconds: Annotated[
        float | None,
        typer.Option(
            "--seconds", min=0.01, metavar="S", help="Length of the take (default: until Ctrl-C)."
        ),
    ] = None,
    label: Annotated[
        list[str] | None,
        typer.Option(
            "--label", "-l", metavar="TARGET=VALUE", help="A label of every touch of the take."
        ),
    ] = None,
) -> None:
    """Record a labelled take into a session folder: OUT/take-NNN.wav plus a row of
    OUT/labels.csv (file,TARGET...), the input of `touchbench extract`.

    Touches detected while recording are shown as they end. Ctrl-C ends the take: the
    audio so far is kept and the labels file stays valid.
    """
    from touchbench.app.services.recording import record_take

    targets = _labels(label or [])

    def show(start: float, end: float, heard: tuple[int, ...]) -> None:
        info(f"touch {start:8.3f}-{end:8.3f} s  channels {', '.join(str(c + 1) for c in heard)}")

    take = record_take(
        out,
        device=device,
        samplerate=samplerate,
        channels=channels,
        seconds=seconds,
        labels=targets,
        on_touch=show,
    )
    lost = f", {take.overflows} block(s) LOST to overflow" if take.overflows else ""
    where = f", labelled in {take.labels}" if targets else ""
    summary = f"{take.path}: {take.seconds:.2f} s, {take.touches} touch(es) detected{lost}{where}"
    if take.interrupted and seconds is not None:
        raise AppError(f"interrupted by Ctrl-C; the take so far is kept: {summary}")
    info(summary)


def _labels(pairs: list[str]) -> dict[str, str]:
    labels = key_values(pairs, "--label", "TARGET=VALUE")
    for target in labels:
        if target.lower() in ("file", "start", "end"):
            raise AppError(f"--label: '{target}' is a column of the labels file, not a target")
    return labels


class Sensor(StrEnum):
    contact_mic = "contact-mic"
    oscillating_link = "oscillating-link"


def simulate_command(
    sensor: Annotated[
        Sensor, typer.Argument(metavar="SENSOR", help="contact-mic or oscillating-link.")
    ],
    out: Annotated[
        Path, typer.Option("--out", "-o", metavar="DIR", help="Folder for recordings + labels.")
    ],
    trials: Annotated[
        int,
        typer.Option(
            "--trials", min=1, metavar="N", help="Sessions (contact-mic) or trials (link)."
        ),
    ] = 12,
    seed: Annotated[
        int, typer.Option("--seed", metavar="S", help="Seed of every random draw.")
    ] = 0,
    as_json: JsonOption = False,
) -> None:
    """Write simulated recordings and their labels CSV.

    contact-mic: sessions of 16 taps and strokes on three contact microphones (44.1 kHz),
    labelled gesture and place by interval; extract with --extractor uc3m-audio.
    oscillating-link: 3 s trials of a motor-shaken link with a 3-axis accelerometer
    (3200 Hz), contact at one of five points or none; extract with --extractor
    band-peaks or mfcc.
    """
    from touchbench.app.services.simulation import write_contact_mic_sessions, write_link_trials

    write = write_contact_mic_sessions if sensor is Sensor.contact_mic else write_link_trials
    paths, labels = write(out, trials=trials, seed=seed)
    if as_json:
        print_json({"recordings": [str(p) for p in paths], "labels": str(labels)})
        return
    info(f"{len(paths)} recording(s) and {labels.name} written to {out}/")
    extractor = "uc3m-audio" if sensor is Sensor.contact_mic else "band-peaks"
    info(f"try: touchbench extract {out}/*.wav --labels {labels} --extractor {extractor}")


def live_command(
    ctx: typer.Context,
    model: Annotated[
        str,
        typer.Option(
            "--model",
            "-m",
            metavar="MODEL",
            help="Model id, NAME (its newest version), NAME@VERSION or NAME@ALIAS; NAME and "
            "NAME@ALIAS are followed: a new version they name answers the next touches.",
        ),
    ],
    device: Annotated[
        str | None,
        typer.Option("--device", "-d", metavar="DEV", help="Capture device index or name."),
    ] = None,
    replay: Annotated[
        Path | None, typer.Option("--replay", metavar="FILE", help="A recording to replay instead.")
    ] = None,
    realtime: Annotated[
        bool, typer.Option("--realtime/--fast", help="Pace a replay in real time.")
    ] = False,
    seconds: Annotated[
        float | None,
        typer.Option("--seconds", min=0.01, metavar="S", help="Stop after this much audio."),
    ] = None,
    topic: Annotated[
        str | None, typer.Option("--topic", metavar="TOPIC", help="Audio topic of a bag.")
    ] = None,
    channels: Annotated[
        int | None,
        typer.Option(
            "--channels", min=1, metavar="N", help="Device channels (default: the model's)."
        ),
    ] = None,
    samplerate: Annotated[
        float | None,
        typer.Option(
            "--samplerate",
            metavar="HZ",
            help=(
                "Device rate in Hz (default: the model's); for a replayed CSV or .npy file, "
                "its rate."
            ),
        ),
    ] = None,
    block_length: Annotated[
        int,
        typer.Option(
            "--block",
            min=16,
            max=65536,
            metavar="SAMPLES",
            help="Samples per block read from the device or file; a touch is predicted once "
            "the block holding its end is in, so smaller blocks answer sooner.",
        ),
    ] = LIVE_BLOCK,
    as_json: Annotated[
        bool, typer.Option("--json", help="One JSON object per touch on stdout (JSON lines).")
    ] = False,
    engine: EngineOption = None,
) -> None:
    """Predict every touch of a live stream with a model: its own event detection and
    extractor run on the stream, and each touch is printed as soon as it ends."""
    from touchbench.app.services.live import LiveSession, follower, load_live_model
    from touchbench.drivers.replay import FileReplaySource
    from touchbench.drivers.sound import SoundDeviceSource
    from touchbench.drivers.source import Source

    if (device is None) == (replay is None):
        raise AppError("give exactly one of --device DEV or --replay FILE")
    from touchbench.app.cli.requests import build_request
    from touchbench.app.schemas.models import EngineChoice

    choice = build_request(EngineChoice, engine=engine)
    store = get_state(ctx).store
    model_info, trained = load_live_model(store, model, choice.engine)
    extraction = model_info.extraction
    source: Source
    if replay is not None:
        source = FileReplaySource(
            replay,
            samplerate=samplerate,
            realtime=realtime,
            topic=topic,
            block_length=block_length,
        )
    else:
        assert device is not None
        recipe = extraction or {}
        source = SoundDeviceSource(
            device,
            samplerate=samplerate or recipe.get("samplerate"),
            channels=channels or recipe.get("n_channels"),
            seconds=seconds,
            block_length=block_length,
        )
    with source:
        session = LiveSession(
            model_info,
            trained,
            samplerate=source.samplerate,
            n_channels=source.n_channels,
            extraction=extraction,
            follow=follower(store, model, model_info, engine=choice.engine),
        )
        shown = 0
        try:
            for block in source.blocks():
                for touch in session.feed(block.samples, block.time, arrived=block.arrived):
                    _show(touch.to_json(), as_json)
                    shown += 1
                _tell(session.take_events())
                if seconds is not None and block.time >= seconds:
                    break
        except KeyboardInterrupt:
            pass
        for touch in session.finish():
            _show(touch.to_json(), as_json)
            shown += 1
    for warning in dict.fromkeys(session.warnings):
        info(f"[yellow]warning:[/yellow] {warning}")
    if source.overflows:
        info(f"[yellow]warning:[/yellow] {source.overflows} block(s) were lost (overflow)")
    if not as_json:
        info(f"{shown} touch(es) recognised")


def _tell(events: list[dict[str, str]]) -> None:
    """What happened to a followed model (``NAME@champion`` moved), on stderr."""
    for event in events:
        if "switched" in event:
            info(f"now predicting with {escape(event['switched'])} (was {escape(event['from'])})")
        else:
            warn(event["warning"])


def _show(touch: dict, as_json: bool) -> None:
    if as_json:
        sys.stdout.write(json.dumps(touch) + "\n")
        sys.stdout.flush()
        return
    said = ", ".join(
        f"{target} {p['value']}" + (f" ({p['probability']:.2f})" if p["probability"] else "")
        for target, p in touch["predictions"].items()
    )
    print(f"{touch['start']:9.3f}-{touch['end']:9.3f} s  {said}  [{touch['latency_ms']:.1f} ms]")
    sys.stdout.flush()
