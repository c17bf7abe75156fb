"""The interface every image processor implements."""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from replay.frames import Frame
    from replay.messages import Message

#: one output message and the name of the output it belongs to (declared in the registry)
Output = tuple[str, "Message"]


class Processor(Protocol):
    """A pure function from one camera frame to output messages, with its options bound.

    It names outputs, not topics: the pipeline puts each output on its topic. ``__call__``
    must not keep state between frames, so that frames can be processed in parallel; output
    messages carry the input's ``stamp_ns`` and ``frame_id``.
    """

    def __call__(self, frame: Frame) -> list[Output]:
        """Output messages for one frame (an output may be absent, e.g. no centroid)."""
        ...
