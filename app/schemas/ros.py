"""The request of the ROS node (``touchbench ros``)."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from touchbench.app.errors import FieldError
from touchbench.app.schemas.models import EngineChoice

#: How the bytes of an audio topic are coded when no ``AudioInfo`` says it.
SampleFormat = Literal["S16LE", "S32LE", "F32LE", "MP3"]


class RosNodeRequest(EngineChoice):
    """A node that predicts every touch of an audio or taxel topic with a stored model and
    publishes each as a ``std_msgs/String`` JSON message."""

    model: str = Field(min_length=1, description="The model's name or id (or NAME@ALIAS).")
    audio_topic: str | None = Field(
        default=None, description="An audio_common_msgs/AudioData topic."
    )
    taxel_topic: str | None = Field(
        default=None,
        description="A std_msgs/Float32MultiArray topic at a fixed rate: one sample of every "
        "taxel per message, or a block (a layout of two dimensions, samples outer).",
    )
    publish: str = Field(default="/touch", min_length=1, description="Topic of the touches.")
    info_topic: str | None = Field(
        default=None,
        description="The AudioInfo topic (default: audio_info beside the audio topic).",
    )
    samplerate: float | None = Field(
        default=None, gt=0, le=1e6, description="Hz (default: AudioInfo's, else the model's)."
    )
    channels: int | None = Field(
        default=None, ge=1, le=4096, description="Channels or taxels (default: the model's)."
    )
    sample_format: SampleFormat | None = Field(
        default=None, description="Audio coding when no AudioInfo is read."
    )
    info_timeout: float = Field(
        default=5.0, gt=0, le=600, description="Seconds to wait for AudioInfo."
    )

    @model_validator(mode="after")
    def _one_topic(self) -> RosNodeRequest:
        if (self.audio_topic is None) == (self.taxel_topic is None):
            raise FieldError("audio_topic", "give exactly one of `audio_topic` or `taxel_topic`")
        if self.taxel_topic is not None:
            for field in ("sample_format", "info_topic"):
                if getattr(self, field) is not None:
                    raise FieldError(field, "is for audio, not with `taxel_topic`")
        return self
