"""The ``ros`` command: a ROS node that publishes the touches a model recognises."""

from __future__ import annotations

from typing import Annotated

import typer

from touchbench.app.cli.output import EngineOption, info
from touchbench.app.cli.requests import build_request
from touchbench.app.cli.signals import deferred_interrupts
from touchbench.app.cli.state import get_state
from touchbench.app.schemas.ros import RosNodeRequest, SampleFormat


def register(app: typer.Typer) -> None:
    app.command("ros")(ros_command)


def ros_command(
    ctx: typer.Context,
    model: Annotated[str, typer.Option("--model", "-m", metavar="MODEL", help="Model name or id.")],
    audio_topic: Annotated[
        str | None,
        typer.Option("--audio-topic", metavar="TOPIC", help="audio_common_msgs/AudioData topic."),
    ] = None,
    taxel_topic: Annotated[
        str | None,
        typer.Option(
            "--taxel-topic",
            metavar="TOPIC",
            help="std_msgs/Float32MultiArray topic at --samplerate: one sample of every taxel "
            "per message (or a block: a layout of 2 dimensions, samples then taxels).",
        ),
    ] = None,
    publish: Annotated[
        str, typer.Option("--publish", metavar="TOPIC", help="std_msgs/String topic of touches.")
    ] = "/touch",
    info_topic: Annotated[
        str | None,
        typer.Option(
            "--info-topic",
            metavar="TOPIC",
            help="AudioInfo topic (default: audio_info beside the audio topic).",
        ),
    ] = None,
    samplerate: Annotated[
        float | None,
        typer.Option(
            "--samplerate", metavar="HZ", help="Hz (default: AudioInfo's or the model's)."
        ),
    ] = None,
    channels: Annotated[
        int | None,
        typer.Option("--channels", metavar="N", help="Channels or taxels (default: the model's)."),
    ] = None,
    sample_format: Annotated[
        str | None,
        typer.Option(
            "--sample-format",
            metavar="FORMAT",
            help="S16LE, S32LE, F32LE or MP3: the audio's coding, when no AudioInfo is read.",
        ),
    ] = None,
    info_timeout: Annotated[
        float | None,
        typer.Option("--info-wait", metavar="S", help="Seconds to wait for AudioInfo (5)."),
    ] = None,
    engine: EngineOption = None,
    as_json: Annotated[
        bool, typer.Option("--json", help="Also print each touch as JSON lines on stdout.")
    ] = False,
) -> None:
    """Run a ROS node that predicts every touch of an audio or taxel topic with a model and
    publishes each as a std_msgs/String JSON message (what `live --json` prints).

    ROS 1 (Debian's rospy) on the master of ROS_MASTER_URI. The audio's format comes from
    its AudioInfo topic (audio_capture latches one), else from --sample-format (and
    --samplerate, --channels when not the model's). Ctrl-C publishes the touches still
    open and stops the node.
    """
    # start-up time: the feature stack, and ROS's modules only for this command
    from touchbench.app.cli.capture import _show
    from touchbench.app.services.ros_node import run_ros_node
    from touchbench.drivers.ros1 import Ros1Transport
    from touchbench.drivers.source import Source

    fmt: SampleFormat | None = sample_format.upper() if sample_format else None  # type: ignore[assignment]
    request = build_request(
        RosNodeRequest,
        {"info_timeout": "--info-wait"},
        model=model,
        audio_topic=audio_topic,
        taxel_topic=taxel_topic,
        publish=publish,
        info_topic=info_topic,
        samplerate=samplerate,
        channels=channels,
        sample_format=fmt,
        info_timeout=info_timeout,
        engine=engine,
    )
    store = get_state(ctx).store
    transport = Ros1Transport("touchbench")

    def ready(source: Source) -> None:
        topic = request.audio_topic or request.taxel_topic
        for note in source.notes:
            info(note)
        info(
            f"listening on {topic} ({source.n_channels} channel(s) at {source.samplerate:g} Hz), "
            f"publishing touches on {request.publish}; Ctrl-C stops"
        )

    try:
        # Ctrl-C stops the node between two messages, never inside the processing of one:
        # what was received is processed and the touches still open are published.
        with deferred_interrupts(transport.stop):
            run_ros_node(
                store,
                request,
                transport,
                on_ready=ready,
                on_touch=lambda touch: _show(touch.to_json(), True) if as_json else None,
            )
    finally:
        transport.close()
