"""Start-up stays light: the parser and the light commands load no heavy library.

Each case runs in a fresh interpreter (this test process has everything loaded already) and
reads ``sys.modules`` at exit, which is deterministic where a time would not be.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

#: libraries only the commands that compute with them may load
HEAVY = ("cv2", "numpy", "rerun", "mujoco", "ray", "matplotlib", "scipy")
#: what opening and summarising a log must not load (no pixel is touched, no protobuf schema)
LOG_HEAVY = ("cv2", "google", "rerun", "mujoco", "ray", "matplotlib", "scipy")
GOLDEN = Path(__file__).parents[3] / "datasets" / "golden"

SCRIPT = """
import json, sys
from camlog.cli import main
try:
    main(sys.argv[1:])
except SystemExit:
    pass
print(json.dumps(sorted({name.split(".")[0] for name in sys.modules})))
"""


def loaded_by(*argv: str) -> set[str]:
    """Top-level packages loaded by ``camlog ARGV...`` in a fresh interpreter."""
    done = subprocess.run([sys.executable, "-c", SCRIPT, *argv], capture_output=True,
                          text=True, check=True)
    return set(json.loads(done.stdout.splitlines()[-1]))


@pytest.mark.parametrize("argv", [
    ["--help"],
    [],
    ["no-such-command"],
    ["view", "--help"],
    ["view"],
    ["info"],
    ["info", "--help"],
    ["golden", "--no-such-option"],
    ["process", "--help"],
    ["resync", "--help"],
    ["throttle", "--help"],
    ["convert", "--help"],
    ["convert", "IN.mcap"],
], ids=" ".join)
def test_help_and_argument_errors_load_no_heavy_library(argv: list[str]) -> None:
    assert loaded_by(*argv) & set(HEAVY) == set()


def test_the_parser_is_built_without_heavy_libraries() -> None:
    script = ("import sys; from camlog.cli import build_parser; build_parser(['view', 'info']); "
              "print(' '.join(sorted(sys.modules)))")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          check=True)
    loaded = {name.split(".")[0] for name in done.stdout.split()}
    assert loaded & set(HEAVY) == set()
    assert "camlog" in loaded  # the parser did load camlog's own modules


def test_info_on_a_log_loads_no_opencv_protobuf_or_viewer() -> None:
    log = GOLDEN / "red_block-seed0-640x480-f10.mcap"
    assert log.is_file()
    loaded = loaded_by("info", str(log))
    assert loaded & set(LOG_HEAVY) == set()
    assert "mcap" in loaded  # the log was read


def test_info_on_an_mcap_log_loads_neither_numpy_nor_rosbags() -> None:
    """Counts and spans come from the index, the first image is described from its bytes."""
    log = GOLDEN / "stereo_unsynced-seed0-640x480-f240.mcap"
    loaded = loaded_by("info", str(log))
    assert {"numpy", "rosbags"} & loaded == set()
    assert "mcap_ros2" in loaded  # the first image and camera info were decoded


def test_convert_without_progress_loads_neither_tqdm_nor_an_image_codec(tmp_path: Path) -> None:
    """Messages are copied as bytes: no image is decoded, no bar is shown."""
    log = GOLDEN / "red_block-seed0-640x480-f10.mcap"
    loaded = loaded_by("convert", str(log), str(tmp_path / "out.bag"), "--no-progress")
    assert (tmp_path / "out.bag").is_file()
    assert {"tqdm", "cv2", "av"} & loaded == set()
    assert "rosbags" in loaded


def test_reading_an_mcap_log_loads_no_other_format_library() -> None:
    log = GOLDEN / "red_block-seed0-640x480-f10.mcap"
    loaded = loaded_by("info", str(log))
    assert "mcap" in loaded
    assert "ruamel" not in loaded  # rosbag2's metadata reader (rosbags' bag formats)
