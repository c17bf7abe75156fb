"""The record of processed outputs: round trip through a message, refusal of what is not one."""

from __future__ import annotations

import json
from dataclasses import replace

import pytest

from replay.display import Display
from replay.errors import RecordError
from replay.messages import Text
from replay.records import ProcessedOutput, ProcessedOutputs, outputs_by_topic

EDGES = ProcessedOutput(topic="/cam/edges", source="/cam/image_raw", processor="edges",
                        output="edges", msgtype="sensor_msgs/msg/Image",
                        display=Display.EDGES.value, entity="edges", label="Canny edges")


def test_round_trip_keeps_every_field() -> None:
    record = ProcessedOutputs([EDGES], {"edges": {"low": 50.0, "high": 150.0}}, "1.2")
    message = record.to_message()
    assert json.loads(message.data)["outputs"][0]["display"] == "edges"
    assert ProcessedOutputs.from_message(message) == record
    assert EDGES.shown_as is Display.EDGES


def test_a_later_record_wins_for_its_topics() -> None:
    later = replace(EDGES, display=Display.IMAGE.value)
    assert outputs_by_topic([ProcessedOutputs([EDGES]), ProcessedOutputs([later])]) == {
        "/cam/edges": later}


def test_an_unknown_display_is_kept_but_not_shown() -> None:
    newer = replace(EDGES, display="hologram")
    assert ProcessedOutputs.from_message(ProcessedOutputs([newer]).to_message()).outputs == [
        newer]
    assert newer.shown_as is None


@pytest.mark.parametrize(("text", "problem"), [
    ("{", "not valid JSON"),
    ("[]", "expected an object"),
    ('{"outputs": [{"topic": "/a"}]}', "missing"),
    ('{"outputs": 3}', "expected a list"),
])
def test_what_is_not_a_record_is_refused(text: str, problem: str) -> None:
    with pytest.raises(RecordError, match=problem):
        ProcessedOutputs.from_message(Text(text))
