"""``camlog throttle``: thinned topics keep their stored bytes; every other topic is whole."""

from __future__ import annotations

from pathlib import Path

import pytest
from mcap.reader import make_reader

from camlog.cli import main

LEFT = "/stereo_camera/left"


def stored(path: Path) -> dict[str, list[tuple[int, bytes]]]:
    """(log time, stored bytes) per topic, read with the mcap library."""
    out: dict[str, list[tuple[int, bytes]]] = {}
    with path.open("rb") as f:
        for _, channel, message in make_reader(f).iter_messages(log_time_order=True):
            out.setdefault(channel.topic, []).append((message.log_time, bytes(message.data)))
    return out


@pytest.mark.parametrize(("flags", "kept"), [
    (["--rate", "10"], list(range(0, 20, 3))),  # 30 Hz stamps: one frame per 100 ms
    (["--every", "4"], list(range(0, 20, 4))),
])
def test_kept_frames_are_the_stored_bytes(red_log: Path, tmp_path: Path, flags: list[str],
                                          kept: list[int],
                                          capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "thin.mcap"
    assert main(["throttle", str(red_log), "-o", str(out), "--topic", f"{LEFT}/image_raw",
                 "--topic", f"{LEFT}/camera_info", *flags]) == 0
    assert capsys.readouterr().out.startswith(f"kept {2 * len(kept)} of 40 messages")
    before, after = stored(red_log), stored(out)
    for topic in (f"{LEFT}/image_raw", f"{LEFT}/camera_info"):
        assert after[topic] == [before[topic][i] for i in kept]
    assert set(after) == set(before)
    for topic in set(before) - {f"{LEFT}/image_raw", f"{LEFT}/camera_info"}:
        assert after[topic] == before[topic]


def test_bad_use_is_one_line(red_log: Path, tmp_path: Path,
                             capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "thin.mcap"
    for flags, needle in ((["--rate", "0"], "--rate: must be > 0"),
                          (["--every", "x"], "--every: expected an integer"),
                          (["--every", "2", "--topic", "/camlog/scenario"],
                           "/camlog/scenario is std_msgs/msg/String")):
        code = main(["throttle", str(red_log), "-o", str(out), "--topic", f"{LEFT}/image_raw",
                     *flags])
        err = capsys.readouterr().err
        assert code == 1 and err.count("\n") == 1 and needle in err, err
        assert not out.exists()
    # one of --rate / --every is required
    assert main(["throttle", str(red_log), "-o", str(out), "--topic", f"{LEFT}/image_raw"]) == 1
    err = capsys.readouterr().err
    assert err == "camlog throttle: error: give --every or --rate\n"
    assert not out.exists()
