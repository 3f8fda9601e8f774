"""The ROS node: a topic of audio or taxels in, one JSON message per touch out.

The model's own recipe runs on the topic through a :class:`~app.services.live.LiveSession`
(as ``touchbench live`` does on a sound card), and every touch is published as a
``std_msgs/String`` holding the object ``live --json`` prints (start, end, per target the
label and its probability, latency).  The middleware is a
:class:`~drivers.ros_transport.RosTransport` given by the caller: ROS 1 today.
"""

from __future__ import annotations

import json
from collections.abc import Callable

from touchbench.app.schemas.ros import RosNodeRequest
from touchbench.app.services.live import LiveSession, TouchPrediction, load_live_model
from touchbench.app.store.database import Store
from touchbench.drivers.ros_source import RosAudioSource, RosTaxelSource, info_topic_of
from touchbench.drivers.ros_transport import RosTransport
from touchbench.drivers.source import Source


def run_ros_node(
    store: Store,
    request: RosNodeRequest,
    transport: RosTransport,
    *,
    on_ready: Callable[[Source], None] | None = None,
    on_touch: Callable[[TouchPrediction], None] | None = None,
) -> int:
    """Publish every touch of the request's topic until the transport is stopped
    (:meth:`~drivers.ros_transport.RosTransport.stop`, on Ctrl-C): the messages received
    before the stop are processed, then the touches still open are published.

    Parameters
    ----------
    on_ready : callable, optional
        Called with the source once subscribed and advertised.
    on_touch : callable, optional
        Called with each touch once published.

    Returns
    -------
    int
        Touches published.
    """
    info, model = load_live_model(store, request.model, request.engine)
    recipe = info.extraction or {}
    samplerate = request.samplerate or recipe.get("samplerate")
    channels = request.channels or recipe.get("n_channels")
    transport.advertise(request.publish)  # first: subscribers connect while we wait
    source: Source
    if request.audio_topic is not None:
        given = request.sample_format is not None
        source = RosAudioSource(
            transport,
            request.audio_topic,
            info_topic=request.info_topic or info_topic_of(request.audio_topic),
            # Given a format, the rest defaults to the model's; else AudioInfo says it.
            samplerate=samplerate if given else request.samplerate,
            channels=channels if given else request.channels,
            sample_format=request.sample_format,
            info_timeout=request.info_timeout,
        )
    else:
        assert request.taxel_topic is not None
        source = RosTaxelSource(
            transport,
            request.taxel_topic,
            samplerate=float(samplerate or 0.0),
            channels=int(channels or 0),
        )
    published = 0

    def publish(touch: TouchPrediction) -> None:
        nonlocal published
        transport.publish(json.dumps(touch.to_json()))
        published += 1
        if on_touch is not None:
            on_touch(touch)

    with source:
        session = LiveSession(
            info, model, samplerate=source.samplerate, n_channels=source.n_channels
        )
        if on_ready is not None:
            on_ready(source)
        for block in source.blocks():
            for touch in session.feed(block.samples, block.time, arrived=block.arrived):
                publish(touch)
        for touch in session.finish():
            publish(touch)
    return published
