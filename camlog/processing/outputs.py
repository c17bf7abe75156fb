"""Where processor outputs go: ``{input namespace}/{output}`` or a chosen namespace.

``/stereo/left/image_raw`` has the namespace ``/stereo/left``, so its edges go to
``/stereo/left/edges``. A chosen output namespace may contain ``{ns}`` for the input's
(``/processed{ns}``), which keeps two cameras apart; ``/image_converter`` gives the names of
the chapter's ROS nodes.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from processors.spec import Configured
from replay.msgtypes import COMPRESSED_IMAGE, IMAGE

from ..errors import UsageError
from ..requests.processing import CHAPTER_NS

if TYPE_CHECKING:  # the command line imports this module: records load numpy
    from replay.records import ProcessedOutput


__all__ = ["CHAPTER_NS", "input_namespace", "output_namespace", "plan_outputs"]



def input_namespace(topic: str) -> str:
    """The namespace of an image topic: ``/cam/image_raw[/compressed]`` -> ``/cam``.

    >>> input_namespace("/stereo/left/image_raw/compressed"), input_namespace("/image")
    ('/stereo/left', '')
    """
    name = topic.removesuffix("/compressed") if topic.endswith("/compressed") else topic
    return name.rpartition("/")[0]


def output_namespace(topic: str, output_ns: str | None) -> str:
    """Namespace of the outputs computed from ``topic``: its own, or ``output_ns`` with
    ``{ns}`` replaced by it.

    >>> output_namespace("/cam/image_raw", None), output_namespace("/cam/image_raw", "/p{ns}")
    ('/cam', '/p/cam')
    """
    if output_ns is None:
        return input_namespace(topic)
    if not output_ns.startswith("/"):
        raise UsageError(f"output namespace {output_ns!r} must start with '/'")
    rest = output_ns.replace("{ns}", "")
    if "{" in rest or "}" in rest or "//" in rest:
        raise UsageError(f"output namespace {output_ns!r}: only {{ns}} may stand in braces, "
                          "and names may not be empty")
    return output_ns.replace("{ns}", input_namespace(topic)).rstrip("/")


def plan_outputs(
    topics: Sequence[str], processors: Sequence[Configured], *, output_ns: str | None,
    compress: str | None,
) -> dict[str, list[list[tuple[str, ProcessedOutput]]]]:
    """Per input topic, per processor: (output name, its declared output with its topic).

    Image outputs go to ``TOPIC/compressed`` as CompressedImage when ``compress`` is set.
    Two outputs on one topic, or an output on an input topic, are refused.
    """
    from replay.records import ProcessedOutput

    plans: dict[str, list[list[tuple[str, ProcessedOutput]]]] = {}
    taken: dict[str, str] = {}
    for source in topics:
        namespace = output_namespace(source, output_ns)
        plans[source] = []
        for configured in processors:
            spec, outputs = configured.spec, []
            for out in spec.outputs:
                topic, msgtype = f"{namespace}/{out.name}", out.msgtype
                if compress and msgtype == IMAGE:
                    topic, msgtype = topic + "/compressed", COMPRESSED_IMAGE
                where = f"{spec.name}'s {out.name} of {source}"
                if topic in taken:
                    raise UsageError(f"{topic} would hold both {taken[topic]} and {where}; "
                                      "choose an output namespace with {ns} in it")
                if topic in topics:
                    raise UsageError(f"{where} would be written to the input topic {topic}")
                taken[topic] = where
                outputs.append((out.name, ProcessedOutput(
                    topic=topic, source=source, processor=spec.name, output=out.name,
                    msgtype=msgtype, display=out.display.value, entity=spec.entity(out),
                    label=out.label)))
            plans[source].append(outputs)
    return plans
