"""OS errors while writing: one line naming the output, exit status 1, nothing left behind.

The file system refuses writes past 60 kB here through RLIMIT_FSIZE (the process gets EFBIG,
"File too large", as it would get ENOSPC from a full disk): it needs no privileges, unlike
mounting a tiny tmpfs. Both take the same paths through camlog.
"""

from __future__ import annotations

import resource
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import REPO_ROOT
from tests.slow import renders

LIMIT_BYTES = 60_000
IMAGES = "/stereo_camera/left/image_raw"


@pytest.fixture(scope="module")
@renders
def noisy_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """red_block with sensor noise (incompressible): 10 frames per camera, 840 kB."""
    path = tmp_path_factory.mktemp("noisy") / "noisy.mcap"
    subprocess.run([sys.executable, "-m", "camlog", "record", "red_block", "--frames", "10",
                    "--resolution", "160x120", "--noise", "8", "-o", str(path),
                    "--no-progress"], cwd=REPO_ROOT, check=True, capture_output=True)
    return path


@pytest.fixture(scope="module")
def image_folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Ten noise PNGs of 160x120."""
    import cv2
    import numpy as np

    folder = tmp_path_factory.mktemp("images")
    for index in range(10):
        pixels = np.random.default_rng(index).integers(0, 256, (120, 160, 3), dtype=np.uint8)
        cv2.imwrite(str(folder / f"frame{index:02d}.png"), pixels)
    return folder


def _limit_file_size() -> None:
    resource.setrlimit(resource.RLIMIT_FSIZE, (LIMIT_BYTES, LIMIT_BYTES))


#: command -> its arguments (LOG: the noisy log, CAL: a calibration log, DIR: images, OUT)
CASES = {
    "record-mcap": ["record", "red_block", "--frames", "10", "--resolution", "160x120",
                    "--noise", "8", "-o", "OUT/run.mcap"],
    "record-rosbag2": ["record", "red_block", "--frames", "10", "--resolution", "160x120",
                       "--noise", "8", "-o", "OUT/run"],
    "record-sqlite3": ["record", "red_block", "--frames", "10", "--resolution", "160x120",
                       "--noise", "8", "--format", "rosbag2-sqlite3", "-o", "OUT/run"],
    "record-ros1": ["record", "red_block", "--frames", "10", "--resolution", "160x120",
                    "--noise", "8", "-o", "OUT/run.bag"],
    "convert": ["convert", "LOG", "OUT/copy.bag"],
    "process": ["process", "LOG", "--topic", IMAGES, "--edges", "-o", "OUT/p.mcap"],
    "resync": ["resync", "LOG", "--left", "/stereo_camera/left", "--right",
               "/stereo_camera/right", "-o", "OUT/r.mcap"],
    "calibrate": ["calibrate", "CAL", "--size", "7x6", "--square", "0.01", "-o", "OUT/cal"],
    "view": ["view", "LOG", "-o", "OUT/v.rrd"],
    "play": ["play", "LOG", "--rate", "100", "-o", "OUT/played.mcap"],
    "import": ["import", "DIR", "-o", "OUT/imported.mcap"],
}


@pytest.mark.slow
@pytest.mark.parametrize("case", sorted(CASES))
def test_write_refused_by_the_os_is_one_line_and_leaves_nothing(
    tmp_path: Path, noisy_log: Path, mono_calibration_log: Path, image_folder: Path, case: str
) -> None:
    out = tmp_path / "out"
    out.mkdir()
    places = {"LOG": noisy_log, "CAL": mono_calibration_log, "DIR": image_folder, "OUT": out}
    args = [next((str(value) + arg[len(key):] for key, value in places.items()
                  if arg.startswith(key)), arg) for arg in CASES[case]]
    quiet = ["--no-progress"] if args[0] not in ("process", "resync") else []
    result = subprocess.run([sys.executable, "-m", "camlog", *args, *quiet],
                            cwd=REPO_ROOT, capture_output=True, text=True, timeout=300,
                            preexec_fn=_limit_file_size, check=False)
    lines = result.stderr.splitlines()
    assert result.returncode == 1, result.stderr
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith(f"camlog {args[0]}: error: cannot write {out}"), lines[0]
    assert "too large" in lines[0] or "disk I/O error" in lines[0], lines[0]  # SQLite's words
    assert list(out.iterdir()) == []
