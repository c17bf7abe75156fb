"""The README's pictures: real rerun viewer screenshots of ``camlog view`` recordings.

Records four tiny scenarios, runs camlog on them as a user would and photographs the
viewer: a mono calibration (``docs/calibration.png``), the stereo pair's calibration with
its rectified images (``docs/rectified.png``), the red-block processors
(``docs/red_block.png``) and a ChArUco calibration through a strongly distorted rational
lens, its raw view, undistorted view and 3D view side by side (``docs/undistorted.png``).
The viewer runs headless on Mesa's software Vulkan (``WGPU_BACKEND=vulkan``; Debian's
``mesa-vulkan-drivers``), bound to 127.0.0.1.

    python -m benchmarks.screenshots [-o docs] [--keep DIR [--reuse]] [--only PNG...]
"""

from __future__ import annotations

import argparse
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from types import TracebackType
from typing import Any, Self

import cv2
import numpy as np

#: the viewer's window in logical points (one pixel each in the headless viewer)
WINDOW = "1280x720"
#: tries at a screenshot before its timeout is an error
SCREENSHOT_ATTEMPTS = 3
#: the longest side of the warm-up screenshot taken before each picture (px)
WARM_UP_PX = 64


def vulkan_driver() -> str | None:
    """Why no Vulkan driver can be used here (None when an ICD is installed)."""
    folders = [Path(p) for p in ("/usr/share/vulkan/icd.d", "/etc/vulkan/icd.d")]
    if not any(folder.is_dir() and any(folder.glob("*.json")) for folder in folders):
        return "no Vulkan driver installed (Debian: apt-get install mesa-vulkan-drivers)"
    return None


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


class Viewer:
    """A headless rerun viewer on 127.0.0.1 that opens recordings and saves screenshots;
    use as a context manager (it ends the viewer's process group on exit)."""

    def __init__(self, home: Path, *, window: str = WINDOW, timeout_s: float = 60.0) -> None:
        self.port = _free_port()
        env = os.environ | {"WGPU_BACKEND": "vulkan", "HOME": str(home),
                            "XDG_CONFIG_HOME": str(home / "config"),
                            "XDG_CACHE_HOME": str(home / "cache"),
                            "XDG_DATA_HOME": str(home / "data")}
        home.mkdir(parents=True, exist_ok=True)
        self._log = (home / "viewer.log").open("w")
        self.process = subprocess.Popen(
            [sys.executable, "-m", "rerun", "--headless", "--bind", "127.0.0.1", "--port",
             str(self.port), "--window-size", window, "--hide-welcome-screen"],
            env=env, stdout=self._log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
            start_new_session=True)
        self.timeout_s = timeout_s
        self.client: Any = None

    def __enter__(self) -> Self:
        from rerun.experimental import ViewerClient

        deadline = time.monotonic() + self.timeout_s
        while not self._listening():
            if self.process.poll() is not None or time.monotonic() > deadline:
                self.close()
                raise RuntimeError(f"the rerun viewer did not start: see {self._log.name}")
            time.sleep(0.1)
        self.client = ViewerClient.connect(f"rerun+http://127.0.0.1:{self.port}/proxy")
        return self

    def _listening(self) -> bool:
        with socket.socket() as probe:
            return probe.connect_ex(("127.0.0.1", self.port)) == 0

    def screenshot(self, rrd: Path, png: Path, *, at: float = 0.5, settle_s: float = 6.0,
                   view_origin: str | None = None) -> Path:
        """Open ``rrd`` and save the viewer in the recording's layout, paused ``at`` this
        fraction of its header_stamp timeline, to ``png``; only the view whose origin is
        ``view_origin`` (e.g. ``/world/cam``) when given."""
        client = self.client
        client.close("all")
        client.open(str(rrd))
        deadline = time.monotonic() + self.timeout_s
        while True:
            state = client.get_state()
            if (not state.loading and state.recordings) or time.monotonic() > deadline:
                break
            time.sleep(0.2)
        (recording, *_) = state.recordings
        timeline = next(t for t in recording.timelines if t.name == "header_stamp")
        instant = round(timeline.start + at * (timeline.end - timeline.start))
        client.set_time("header_stamp", timestamp=np.datetime64(instant, "ns"),
                        play_state="paused")
        time.sleep(settle_s)  # let the software renderer draw and the notices fade
        view_id = None
        if view_origin is not None:
            views = client.get_state().views
            view_id = next((v.view_id for v in views if v.origin == view_origin), None)
            if view_id is None:
                raise RuntimeError(f"no view of {view_origin} in {[v.origin for v in views]}")
        raw = png.with_suffix(".raw.png")
        for attempt in range(SCREENSHOT_ATTEMPTS):
            try:  # the software renderer's first frame of a new kind of view can time out,
                # and paint before every image is uploaded: the first is a warm-up
                client.take_screenshot(view_id, max_size=WARM_UP_PX)
                time.sleep(settle_s / 2)
                client.save_screenshot(str(raw), view_id)
                break
            except TimeoutError:
                if attempt == SCREENSHOT_ATTEMPTS - 1:
                    raise
        pixels = cv2.imread(str(raw), cv2.IMREAD_COLOR)
        raw.unlink()
        if pixels is None:
            raise RuntimeError(f"the viewer saved no readable screenshot of {rrd}")
        cv2.imwrite(str(png), pixels, [cv2.IMWRITE_PNG_COMPRESSION, 9])
        return png

    def close(self) -> None:
        """End the viewer (its whole process group)."""
        for sig in (signal.SIGTERM, signal.SIGKILL):
            try:
                os.killpg(self.process.pid, sig)
                self.process.wait(timeout=10)
                break
            except ProcessLookupError:
                break
            except subprocess.TimeoutExpired:
                continue
        self._log.close()

    def __exit__(self, et: type[BaseException] | None, ev: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()


#: README picture -> the recording it shows
RECORDINGS = {"calibration.png": "mono.rrd", "rectified.png": "stereo.rrd",
              "red_block.png": "red.rrd", "undistorted.png": "lens.rrd"}
#: pictures made of views side by side: picture -> the views' origins
SIDE_BY_SIDE = {"undistorted.png": ("/raw/charuco_camera", "/world/charuco_camera/undistorted",
                                    "/world")}
#: the height every view of a side-by-side picture is scaled to (px)
SIDE_HEIGHT = 420


def camlog(*argv: str) -> None:
    """``camlog ARGV… --overwrite`` in a fresh process, as a user types it (a --keep folder
    made before is made again)."""
    subprocess.run([sys.executable, "-m", "camlog", *argv, "--overwrite"], check=True,
                   stdout=subprocess.DEVNULL)


def _mono(work: Path) -> None:
    camlog("record", "mono_checkerboard", "--frames", "90", "-o", str(work / "mono.mcap"), QUIET)
    camlog("calibrate", str(work / "mono.mcap"), "--size", "7x6", "--square", "0.01",
           "-o", str(work / "mono_cal"), QUIET)
    camlog("view", str(work / "mono_cal" / "calibration.mcap"), "-o", str(work / "mono.rrd"),
           QUIET)


def _stereo(work: Path) -> None:
    camlog("record", "stereo_unsynced", "--duration", "4", "-o", str(work / "stereo.mcap"),
           QUIET)
    camlog("resync", str(work / "stereo.mcap"), "-o", str(work / "synced.mcap"))
    camlog("calibrate", str(work / "synced.mcap"), "--size", "7x6", "--square", "0.01",
           "--left", "/stereo_sync/left", "--right", "/stereo_sync/right",
           "-o", str(work / "stereo_cal"), QUIET)
    camlog("view", str(work / "stereo_cal" / "calibration.mcap"), "-o",
           str(work / "stereo.rrd"), QUIET)


def _red(work: Path) -> None:
    camlog("record", "red_block", "--frames", "30", "-o", str(work / "red.mcap"), QUIET)
    camlog("process", str(work / "red.mcap"), "--topic", "/stereo_camera/left/image_raw",
           "--red-pixels", "--edges", "-o", str(work / "red_out.mcap"))
    camlog("view", str(work / "red_out.mcap"), "-o", str(work / "red.rrd"), QUIET)


def _lens(work: Path) -> None:
    """A strongly distorted rational lens calibrated on a ChArUco board: the raw image with
    its overlays, the undistorted view with the board where the calibration solved it, and
    the camera in 3D."""
    camlog("record", "mono_charuco", "--frames", "120", "-o", str(work / "lens.mcap"), QUIET)
    camlog("calibrate", str(work / "lens.mcap"), "--pattern", "charuco", "--size", "8x6",
           "--square", "0.011", "--marker", "0.008", "--model", "rational_polynomial",
           "-o", str(work / "lens_cal"), QUIET)
    camlog("view", str(work / "lens_cal" / "calibration.mcap"), "-o", str(work / "lens.rrd"),
           QUIET)


QUIET = "--no-progress"
#: picture -> how its recording is made in a work folder
RECIPES = {"calibration.png": _mono, "rectified.png": _stereo, "red_block.png": _red,
           "undistorted.png": _lens}


def side_by_side(viewer: Viewer, rrd: Path, png: Path, origins: tuple[str, ...], *,
                 at: float = 0.5) -> Path:
    """One picture of the views of ``rrd`` whose origins are ``origins``, each scaled to
    :data:`SIDE_HEIGHT`, left to right, with a thin gap."""
    parts = []
    for index, origin in enumerate(origins):
        shot = viewer.screenshot(rrd, png.with_name(f"{png.stem}.{index}.png"), at=at,
                                 view_origin=origin)
        pixels = cv2.imread(str(shot), cv2.IMREAD_COLOR)
        shot.unlink()
        if pixels is None:
            raise RuntimeError(f"the viewer saved no readable screenshot of {origin}")
        height, width = pixels.shape[:2]
        parts.append(cv2.resize(pixels, (round(width * SIDE_HEIGHT / height), SIDE_HEIGHT),
                                interpolation=cv2.INTER_AREA))
        parts.append(np.full((SIDE_HEIGHT, 6, 3), 255, np.uint8))
    cv2.imwrite(str(png), np.hstack(parts[:-1]), [cv2.IMWRITE_PNG_COMPRESSION, 9])
    return png


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", type=Path, default=Path("docs"),
                        help="folder for the PNG files (default docs)")
    parser.add_argument("--keep", type=Path, help="keep the logs and .rrd files here")
    parser.add_argument("--reuse", action="store_true",
                        help="with --keep: photograph the .rrd files already there")
    parser.add_argument("--only", nargs="+", choices=sorted(RECORDINGS), metavar="PNG",
                        help="make only these pictures")
    args = parser.parse_args()
    missing = vulkan_driver()
    if missing:
        sys.exit(f"benchmarks.screenshots: {missing}")
    with tempfile.TemporaryDirectory() as tmp_name:
        work = args.keep or Path(tmp_name)
        work.mkdir(parents=True, exist_ok=True)
        recordings = {name: work / rrd for name, rrd in RECORDINGS.items()
                      if not args.only or name in args.only}
        if not args.reuse:
            for name in recordings:
                RECIPES[name](work)
        args.output.mkdir(parents=True, exist_ok=True)
        for name, rrd in recordings.items():
            # a fresh viewer each: one keeps the first layout it saw per application id
            with Viewer(work / "viewer_home") as viewer:
                if name in SIDE_BY_SIDE:
                    png = side_by_side(viewer, rrd, args.output / name, SIDE_BY_SIDE[name])
                else:
                    png = viewer.screenshot(rrd, args.output / name)
            print(f"{png}  {png.stat().st_size / 1e3:.0f} kB  (from {rrd.name})")
        if args.keep is None:
            shutil.rmtree(work / "viewer_home", ignore_errors=True)


if __name__ == "__main__":
    main()
