"""The interface every image processor implements."""

from __future__ import annotations

from typing import Protocol

from replay.messages import Image, Message

#: one output message and the topic it goes to
Output = tuple[str, Message]


class Processor(Protocol):
    """A pure function from one image to output messages, with its options bound.

    ``outputs()`` names every topic the processor may publish and its ROS 2 type (image
    outputs are ``sensor_msgs/msg/Image``; the pipeline may compress them). ``__call__``
    must not keep state between frames, so that frames can be processed in parallel; output
    messages carry the input's ``stamp_ns`` and ``frame_id``.
    """

    name: str

    def outputs(self) -> dict[str, str]:
        """Output topic -> ROS 2 type name."""
        ...

    def __call__(self, image: Image) -> list[Output]:
        """Output messages for one frame (a topic may be absent, e.g. no centroid)."""
        ...
