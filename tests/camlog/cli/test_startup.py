"""Start-up stays light: the parser and the light commands load no heavy library.

Each case runs in a fresh interpreter (this test process has everything loaded already) and
reads ``sys.modules`` at exit, which is deterministic where a time would not be.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from camlog.cli import COMMANDS

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


@pytest.mark.slow
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


@pytest.mark.slow
@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_every_command_s_help_loads_no_heavy_library(command: str) -> None:
    """Each command's parser takes its choices and defaults from light modules
    (``replay.format_names``, ``recorder.builtin``, ``processors.calibration.patterns``)."""
    assert loaded_by(command, "--help") & set(HEAVY) == set()


@pytest.mark.slow
def test_the_parser_is_built_without_heavy_libraries() -> None:
    script = ("import sys; from camlog.cli import build_parser; build_parser(['view', 'info']); "
              "print(' '.join(sorted(sys.modules)))")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          check=True)
    loaded = {name.split(".")[0] for name in done.stdout.split()}
    assert loaded & set(HEAVY) == set()
    assert "camlog" in loaded  # the parser did load camlog's own modules


@pytest.mark.slow
def test_info_on_a_log_loads_no_opencv_protobuf_or_viewer() -> None:
    log = GOLDEN / "red_block-seed0-640x480-f10.mcap"
    assert log.is_file()
    loaded = loaded_by("info", str(log))
    assert loaded & set(LOG_HEAVY) == set()
    assert "mcap" in loaded  # the log was read


@pytest.mark.slow
def test_info_on_an_mcap_log_loads_neither_numpy_nor_rosbags() -> None:
    """Counts and spans come from the index, the first image is described from its bytes."""
    log = GOLDEN / "stereo_unsynced-seed0-640x480-f240.mcap"
    loaded = loaded_by("info", str(log))
    assert {"numpy", "rosbags"} & loaded == set()
    assert "mcap_ros2" in loaded  # the first image and camera info were decoded


@pytest.mark.slow
def test_convert_without_progress_loads_neither_tqdm_nor_an_image_codec(tmp_path: Path) -> None:
    """Messages are copied as bytes: no image is decoded, no bar is shown."""
    log = GOLDEN / "red_block-seed0-640x480-f10.mcap"
    loaded = loaded_by("convert", str(log), str(tmp_path / "out.bag"), "--no-progress")
    assert (tmp_path / "out.bag").is_file()
    assert {"tqdm", "cv2", "av"} & loaded == set()
    assert "rosbags" in loaded


@pytest.mark.slow
def test_reading_an_mcap_log_loads_no_other_format_library() -> None:
    log = GOLDEN / "red_block-seed0-640x480-f10.mcap"
    loaded = loaded_by("info", str(log))
    assert "mcap" in loaded
    assert "ruamel" not in loaded  # rosbag2's metadata reader (rosbags' bag formats)


def run_loading(*argv: str) -> tuple[subprocess.CompletedProcess[str], set[str]]:
    """``camlog ARGV...`` in a fresh interpreter: the finished process and the top-level
    packages it loaded (None entries, marked absent, included)."""
    done = subprocess.run([sys.executable, "-c", SCRIPT, *argv], capture_output=True,
                          text=True, check=True)
    return done, set(json.loads(done.stdout.splitlines()[-1]))


@pytest.mark.slow
@pytest.mark.parametrize("command", ["view", "convert", "record"])
def test_an_existing_output_is_refused_before_the_heavy_start_up(
        command: str, tmp_path: Path) -> None:
    log = GOLDEN / "red_block-seed0-640x480-f10.mcap"
    existing = tmp_path / {"view": "out.rrd", "convert": "out.bag", "record": "out.mcap"}[command]
    existing.write_bytes(b"the user's file")
    argv = {"view": ["view", str(log), "-o", str(existing)],
            "convert": ["convert", str(log), str(existing)],
            "record": ["record", "-o", str(existing), "--duration", "0.1"]}[command]
    done, loaded = run_loading(*argv)
    assert f"{existing} exists (pass --overwrite to replace it)" in done.stderr
    assert existing.read_bytes() == b"the user's file"
    assert set(HEAVY) & loaded == set()


@pytest.mark.slow
def test_view_refuses_to_write_over_its_log_before_loading_rerun(tmp_path: Path) -> None:
    log = tmp_path / "run.mcap"
    log.write_bytes((GOLDEN / "red_block-seed0-640x480-f10.mcap").read_bytes())
    done, loaded = run_loading("view", str(log), "-o", str(log), "--overwrite")
    assert "is the input" in done.stderr
    assert log.read_bytes() == (GOLDEN / "red_block-seed0-640x480-f10.mcap").read_bytes()
    assert "rerun" not in loaded


@pytest.mark.slow
def test_view_keeps_pyarrow_from_loading_pandas(tmp_path: Path) -> None:
    """pyarrow imports an installed pandas on its first list conversion (0.3-0.4 s); the
    test extra installs pandas (with rerun-sdk[catalog]), so the check below is live."""
    from importlib.util import find_spec

    assert find_spec("pandas") is not None
    log = GOLDEN / "red_block-seed0-640x480-f10.mcap"
    out = tmp_path / "out.rrd"
    as_program = SCRIPT.replace("main(sys.argv[1:])", "main()")  # the camlog program
    done = subprocess.run([sys.executable, "-c", as_program, "view", str(log), "-o", str(out),
                           "--no-progress"], capture_output=True, text=True, check=True)
    loaded = set(json.loads(done.stdout.splitlines()[-1]))
    assert out.stat().st_size > 0
    assert "rerun" in loaded and "pandas" not in loaded
    assert done.stderr == ""  # e.g. no RerunWarning: every component converted


@pytest.mark.slow
def test_main_called_by_other_code_leaves_its_pandas_importable(tmp_path: Path) -> None:
    """Code that calls camlog's main() keeps its pandas (pyarrow would remember it absent)."""
    script = ("import sys; from camlog.cli import main; main(sys.argv[1:]); import pandas; "
              "print(pandas.__name__)")
    log = GOLDEN / "red_block-seed0-640x480-f10.mcap"
    done = subprocess.run([sys.executable, "-c", script, "view", str(log), "-o",
                           str(tmp_path / "out.rrd"), "--no-progress"], capture_output=True,
                          text=True, check=True)
    assert done.stdout.splitlines()[-1] == "pandas"


@pytest.mark.slow
def test_calibrate_with_its_report_loads_no_bar_plotting_or_viewer_library(
        mono_calibration_log: Path, tmp_path: Path) -> None:
    """The figures are drawn with OpenCV; no bar is shown without a terminal."""
    loaded = loaded_by("calibrate", str(mono_calibration_log), "--size", "7x6", "--square",
                       "0.01", "-o", str(tmp_path / "cal"), "--no-progress")
    assert (tmp_path / "cal" / "calibration.mcap").is_file()
    assert {"tqdm", "matplotlib", "scipy", "rerun"} & loaded == set()
    assert "cv2" in loaded


BLAS_SCRIPT = """
import os, sys, threading
from camlog.cli import main
sys.argv = ["camlog", "--help"]  # main() without arguments: camlog is the program
try:
    main({argv})
except SystemExit:
    pass
import numpy
# the main thread and the threads Python did not start (OpenBLAS's)
native = len(os.listdir("/proc/self/task")) - threading.active_count() + 1
print(native, os.environ.get("OPENBLAS_NUM_THREADS"))
"""


@pytest.mark.slow
@pytest.mark.skipif(not Path("/proc/self/task").is_dir(), reason="counts threads in /proc")
def test_numpy_loads_with_one_blas_thread_unless_told_otherwise() -> None:
    """camlog's linear algebra is small: OpenBLAS starts no thread of its own."""
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    threads = {}
    for given in (None, "2"):
        if given is not None:
            env["OPENBLAS_NUM_THREADS"] = given
        done = subprocess.run([sys.executable, "-c", BLAS_SCRIPT.format(argv="")],
                              capture_output=True, text=True, check=True, env=env)
        threads[given] = int(done.stdout.splitlines()[-1].split()[0])
    assert threads == {None: 1, "2": 2}


@pytest.mark.slow
def test_a_caller_of_main_keeps_its_blas_threads() -> None:
    """Called from other code with its arguments, main() leaves the process's settings."""
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    done = subprocess.run([sys.executable, "-c", BLAS_SCRIPT.format(argv='["--help"]')],
                          capture_output=True, text=True, check=True, env=env)
    assert done.stdout.splitlines()[-1].split()[1] == "None"
