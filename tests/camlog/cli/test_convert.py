"""``camlog convert`` through the command line, and the real T265 ROS1 bag through it."""

from __future__ import annotations

from pathlib import Path

import pytest
from rosbags.highlevel import AnyReader

from camlog.cli import main
from replay import open_reader
from tests.rrd import rerun_cli


def raw(path: Path) -> list[tuple[str, int, bytes]]:
    with open_reader(path) as reader:
        return [(r.topic, r.log_time_ns, bytes(r.data)) for r in reader.raw_messages()]


def test_convert_with_compression(red_log: Path, tmp_path: Path,
                                  capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "jpeg"
    assert main(["convert", str(red_log), str(out), "--format", "rosbag2-sqlite3",
                 "--compress", "jpeg", "--topics", "/stereo_camera/left/image_raw",
                 "--no-progress"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("converted 20 messages (20 images re-encoded) to rosbag2")
    assert lines[1] == ("renamed /stereo_camera/left/image_raw -> "
                        "/stereo_camera/left/image_raw/compressed")
    with AnyReader([out]) as reader:
        assert [c.topic for c in reader.connections] == ["/stereo_camera/left/image_raw/"
                                                         "compressed"]
    assert main(["convert", str(red_log), str(out), "--no-progress"]) == 1
    assert "exists (pass --overwrite" in capsys.readouterr().err
    with pytest.raises(SystemExit) as usage:
        main(["convert", str(red_log), str(tmp_path / "x.mcap"), "--compress", "png",
              "--decompress"])
    assert usage.value.code == 2 and "not allowed with" in capsys.readouterr().err


@pytest.mark.slow
@pytest.mark.realdata
def test_real_ros1_bag_to_mcap_and_back(realdata_dir: Path, tmp_path: Path) -> None:
    bag = realdata_dir / "t265_ros1_bag" / "trimmed_locoffice.bag"
    if not bag.is_file():
        pytest.skip(f"real data not found at {bag} (set CAMLOG_REALDATA to its folder)")
    mcap, back = tmp_path / "t265.mcap", tmp_path / "back.bag"
    assert main(["convert", str(bag), str(mcap), "--no-progress"]) == 0
    assert main(["convert", str(mcap), str(back), "--no-progress"]) == 0
    original, returned = raw(bag), raw(back)
    assert len(original) == len(returned) == 50
    # ROS 2 headers have no seq: ROS1 -> CDR -> ROS1 keeps every byte but Header.seq
    # (the first uint32 of these messages), which comes back as 0
    for (topic, t, data), (topic2, t2, data2) in zip(original, returned, strict=True):
        assert (topic, t, data[4:]) == (topic2, t2, data2[4:])
        assert data2[:4] == b"\0\0\0\0"
    assert any(data[:4] != b"\0\0\0\0" for _, _, data in original)
    converted = rerun_cli("mcap", "convert", str(mcap), "-o", str(tmp_path / "t.rrd"),
                          cwd=tmp_path)
    assert converted.returncode == 0, converted.stderr
    with AnyReader([back]) as reader:
        assert sum(1 for _ in reader.messages()) == 50
