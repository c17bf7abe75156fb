"""``camlog view`` through the command line, including the real T265 ROS1 bag."""

from __future__ import annotations

import socket
from pathlib import Path

import pytest

from camlog.cli import main
from tests.recordings import chunked_camera_log, corrupt_middle_chunk
from tests.rrd import load_rrd, rerun_cli


@pytest.mark.slow
def test_view_writes_an_rrd_beside_the_log(red_processed_log: Path, tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    log = tmp_path / "run.mcap"
    log.write_bytes(red_processed_log.read_bytes())
    assert main(["view", str(log), "--no-progress"]) == 0
    out, err = capsys.readouterr()
    # 40 raw 320x240 rgb8 images of 230400 bytes each, announced before writing
    assert out.splitlines()[0] == "images to write: about 9 MB before compression"
    assert out.splitlines()[1].startswith("logged 202 messages (40 images, 2 cameras: "
                                          "/stereo_camera/left, /stereo_camera/right)")
    assert out.splitlines()[-1] == f"wrote {tmp_path / 'run.rrd'}" and err == ""
    verify = rerun_cli("rrd", "verify", "run.rrd", cwd=tmp_path)
    assert verify.returncode == 0, verify.stderr
    assert main(["view", str(log), "--no-progress"]) == 1  # exists: refuse
    assert "exists (pass --overwrite" in capsys.readouterr().err
    assert main(["view", str(log), "--overwrite", "--every", "5", "--jpeg-quality", "70",
                 "--no-ground-truth", "--no-progress"]) == 0
    rec = load_rrd(tmp_path / "run.rrd")
    assert rec.count("/world/stereo_camera/left/image", "EncodedImage:blob") == 4
    assert "/world/stereo_camera/left/ground_truth/red_block" not in rec.rows


@pytest.mark.parametrize(("argv", "message"), [
    (["view", "{missing}"], "does not exist"),
    (["view", "{corrupt}"], "is corrupt (CRC"),
    (["view", "{log}", "--topics", "/nothing"], "has no topic matching '/nothing'"),
    (["view", "{log}", "--start", "3", "--end", "1"], "--end (1.0 s) must be after --start"),
    (["view", "{log}", "-o", "{tmp}/x.png"], "must end in .rrd"),
    (["view", "{log}", "--connect", "nowhere"], "not a viewer address: 'nowhere'"),
    (["view", "{log}", "--connect", "127.0.0.1:{port}"], "no rerun viewer is listening at"),
])
def test_errors_are_one_line(argv: list[str], message: str, red_log: Path, tmp_path: Path,
                             capsys: pytest.CaptureFixture[str]) -> None:
    corrupt = tmp_path / "corrupt.mcap"
    chunked_camera_log(corrupt)
    corrupt_middle_chunk(corrupt)
    with socket.socket() as probe:  # a loopback port nobody listens on
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    names = {"missing": tmp_path / "missing.mcap", "corrupt": corrupt, "log": red_log,
             "tmp": tmp_path, "port": port}
    assert main([a.format(**names) for a in argv]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("camlog view: error: ") and message in err
    assert not list(tmp_path.glob("*.rrd*"))


def test_bad_option_values_are_usage_errors(red_log: Path,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    for option in (["--every", "0"], ["--jpeg-quality", "101"]):
        with pytest.raises(SystemExit) as exit_info:
            main(["view", str(red_log), *option])
        assert exit_info.value.code == 2
        assert "expected" in capsys.readouterr().err


@pytest.mark.slow
@pytest.mark.realdata
def test_real_t265_bag(realdata_dir: Path, tmp_path: Path,
                       capsys: pytest.CaptureFixture[str]) -> None:
    bag = realdata_dir / "t265_ros1_bag" / "trimmed_locoffice.bag"
    if not bag.is_file():
        pytest.skip(f"real data not found at {bag} (set CAMLOG_REALDATA to its folder)")
    assert main(["info", str(bag)]) == 0
    assert "/camera/fisheye1/image_raw" in capsys.readouterr().out
    out = tmp_path / "t265.rrd"
    assert main(["view", str(bag), "-o", str(out), "--no-progress"]) == 0
    printed = capsys.readouterr().out
    assert "not shown: /camera/odom/sample: nav_msgs/msg/Odometry is not shown" in printed
    rec = load_rrd(out)
    for camera in ("fisheye1", "fisheye2"):
        assert rec.count(f"/world/camera/{camera}/image", "Image:buffer") == 3
    (image_format,) = rec.column("/world/camera/fisheye1/image", "Image:format")[:1]
    assert (image_format[0]["width"], image_format[0]["height"]) == (848, 800)
    assert rec.entities_with("Pinhole:image_from_camera") == []  # the bag has no camera_info
    verify = rerun_cli("rrd", "verify", str(out), cwd=tmp_path)
    assert verify.returncode == 0, verify.stderr


def test_view_suggests_jpeg_for_large_raw_images(red_log: Path, tmp_path: Path,
                                                 monkeypatch: pytest.MonkeyPatch,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    import rerun_export.view

    monkeypatch.setattr(rerun_export.view, "LARGE_BYTES", 5_000_000)  # this log: 9.2 MB
    assert main(["view", str(red_log), "-o", str(tmp_path / "a.rrd"), "--no-progress"]) == 0
    first = capsys.readouterr().out.splitlines()[0]
    assert first == ("images to write: about 9 MB before compression; 9 MB of raw images: "
                     "--jpeg-quality 90 stores them as JPEG, several times smaller, --every N "
                     "keeps every N-th frame")
    assert main(["view", str(red_log), "-o", str(tmp_path / "b.rrd"), "--every", "4",
                 "--jpeg-quality", "80", "--no-progress"]) == 0
    assert capsys.readouterr().out.splitlines()[0] == (
        "images to write: about 2 MB before compression (the raw ones as JPEG of quality 80)")
