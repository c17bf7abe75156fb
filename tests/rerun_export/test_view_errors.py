"""``view_logs`` on bad input: one clear error, and no .rrd left behind."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from replay import LogFormatError, LogReadError, OutputError, TopicError
from rerun_export import view_logs
from rerun_export.errors import ViewerError
from tests.outputs import temp_outputs
from tests.recordings import chunked_camera_log, corrupt_middle_chunk
from tests.rerun_export.test_recordings import T0, camera_log
from tests.rrd import load_rrd


def test_a_corrupt_log_fails_and_writes_nothing(tmp_path: Path) -> None:
    log = tmp_path / "bad.mcap"
    chunked_camera_log(log)
    corrupt_middle_chunk(log)
    out = tmp_path / "bad.rrd"
    with pytest.raises(LogReadError, match=r"corrupt .*--recover"):
        view_logs([log], output=out, progress=False)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.mcap"]


def test_recover_shows_everything_but_the_damaged_chunk(tmp_path: Path) -> None:
    log = tmp_path / "bad.mcap"
    stamps = chunked_camera_log(log)
    damaged_from = corrupt_middle_chunk(log)
    out = tmp_path / "bad.rrd"
    result = view_logs([log], output=out, progress=False, recover=True)
    (skipped,) = [w for w in result.warnings if "skipped the damaged chunk" in w]
    first_ns, last_ns = (int(t) for t in re.findall(r"log times (\d+) to (\d+) ns", skipped)[0])
    assert first_ns == damaged_from
    lost = sum(1 for s in stamps if first_ns <= s <= last_ns)
    assert 0 < lost < len(stamps) // 2  # the chunks after the damaged one are shown too
    assert load_rrd(out).count("/world/cam/image", "Image:buffer") == len(stamps) - lost


def test_a_truncated_log_shows_its_complete_chunks(tmp_path: Path) -> None:
    log = tmp_path / "cut.mcap"
    chunked_camera_log(log)
    log.write_bytes(log.read_bytes()[: log.stat().st_size // 2])
    result = view_logs([log], output=tmp_path / "cut.rrd", progress=False)
    images = load_rrd(tmp_path / "cut.rrd").count("/world/cam/image", "Image:buffer")
    assert 0 < images < 40 and any("incomplete" in w for w in result.warnings)


@pytest.mark.parametrize(("content", "error", "match"), [
    (None, LogReadError, "does not exist"),
    (b"", LogReadError, "is empty"),
    (b"not a log", LogFormatError, "not a log camlog can read"),
])
def test_missing_empty_and_unknown_inputs(tmp_path: Path, content: bytes | None, error: type,
                                          match: str) -> None:
    log = tmp_path / "in.mcap"
    if content is not None:
        log.write_bytes(content)
    with pytest.raises(error, match=match):
        view_logs([log], output=tmp_path / "out.rrd", progress=False)
    assert not (tmp_path / "out.rrd").exists()
    assert temp_outputs(tmp_path) == []


def test_output_rules(red_log: Path, tmp_path: Path) -> None:
    out = tmp_path / "x.rrd"
    out.write_text("keep me")
    with pytest.raises(OutputError, match="exists"):
        view_logs([red_log], output=out, progress=False)
    assert out.read_text() == "keep me"
    with pytest.raises(ViewerError, match=r"must end in \.rrd"):
        view_logs([red_log], output=tmp_path / "x.mcap", progress=False)
    with pytest.raises(ViewerError, match="not a viewer address"):
        view_logs([red_log], connect="nowhere", progress=False)
    with pytest.raises(TopicError, match="no topic matching '/nope'"):
        view_logs([red_log], output=tmp_path / "y.rrd", topics=["/nope"],
                  progress=False)


def test_connect_needs_a_listening_viewer(red_log: Path) -> None:
    import socket

    with socket.socket() as probe:  # a loopback port nobody listens on
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    with pytest.raises(ViewerError, match=f"no rerun viewer is listening at .*:{port}/proxy"):
        view_logs([red_log], connect=f"127.0.0.1:{port}", progress=False)


@pytest.mark.parametrize("stage", ["flush_recording", "_disconnect", "combine_recordings"])
def test_ctrl_c_at_any_stage_of_writing_leaves_no_rrd(
        red_log: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, stage: str) -> None:
    """A Ctrl-C while rerun writes the last data, lets go of the file or the recordings are
    combined: nothing at the output, no temporary file beside it."""
    from rerun_export import sink

    real = getattr(sink, stage)

    def interrupted(*args: object, **kwargs: object) -> object:
        real(*args, **kwargs)  # the work is done, then the signal comes (every time)
        raise KeyboardInterrupt

    monkeypatch.setattr(sink, stage, interrupted)
    logs = [red_log]
    if stage == "combine_recordings":  # a log of another rig: a recording of its own
        logs.append(camera_log(tmp_path / "rear.mcap", "/rear", T0))
    with pytest.raises(KeyboardInterrupt):
        view_logs(logs, output=tmp_path / "out.rrd", progress=False)
    assert not (tmp_path / "out.rrd").exists()
    assert temp_outputs(tmp_path) == []
