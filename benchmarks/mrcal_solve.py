"""Run ``mrcal-calibrate-cameras`` on given corners: JSON request on stdin, JSON models out.

Runs under a Python that has mrcal (≥ 3.12 for its wheels), not camlog's: it imports only the
standard library and mrcal. The request::

    {"lensmodel": "LENSMODEL_OPENCV5", "focal_px": 1000, "size": [640, 480],
     "cols": 7, "rows": 6, "spacing_m": 0.01,
     "cameras": [{"frames": {"12": [[u, v] or null, ...  cols * rows points]}}, ...]}

Frame numbers shared between cameras mark one instant seen by both. The answer: per camera
``intrinsics`` (mrcal's: fx, fy, cx, cy, then OpenCV's distortion order) and ``rt_cam_ref``
(camera 0 is the reference), and mrcal's ``report`` (RMS, outliers, board warp), or
``{"error": "..."}``.

    python benchmarks/mrcal_solve.py < request.json
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

TOOL = "mrcal-calibrate-cameras"


def corners_vnl(cameras: list[dict[str, Any]]) -> tuple[str, list[str]]:
    """mrgingham's corners cache (``# filename x y level``; level ``-``: not seen) for the
    cameras' frames (files ``camC-NNNNNN.png``), and one glob per camera."""
    lines = ["# filename x y level"]
    for c, camera in enumerate(cameras):
        for number, points in sorted(camera["frames"].items(), key=lambda kv: int(kv[0])):
            name = f"cam{c}-{int(number):06d}.png"
            lines += [f"{name} - - -" if p is None else f"{name} {p[0]!r} {p[1]!r} 0"
                      for p in points]
    return "\n".join(lines) + "\n", [f"cam{c}-*.png" for c in range(len(cameras))]


def tool_path() -> str:
    """``mrcal-calibrate-cameras`` beside this Python, else on PATH."""
    beside = Path(sys.executable).parent / TOOL
    found = str(beside) if beside.exists() else shutil.which(TOOL)
    if found is None:
        raise FileNotFoundError(f"no {TOOL} beside {sys.executable} or on PATH")
    return found


def solve(request: dict[str, Any], workdir: Path) -> dict[str, Any]:
    """Calibrate as ``mrcal-calibrate-cameras`` does by default (outlier rejection,
    regularisation, board warp), seeded with ``focal_px``."""
    import mrcal  # only under the mrcal Python

    text, globs = corners_vnl(request["cameras"])
    (workdir / "corners.vnl").write_text(text)
    width, height = request["size"]
    done = subprocess.run(
        [sys.executable, tool_path(), "--corners-cache", "corners.vnl",
         "--lensmodel", request["lensmodel"], "--focal", str(request["focal_px"]),
         "--imagersize", str(width), str(height),
         "--object-spacing", str(request["spacing_m"]),
         "--object-width-n", str(request["cols"]), "--object-height-n", str(request["rows"]),
         "--outdir", ".", *globs],
        cwd=workdir, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        tail = (done.stderr.strip() or done.stdout.strip()).splitlines()[-1:] or ["no output"]
        return {"error": f"{TOOL} exited {done.returncode}: {tail[0]}"}
    cameras = []
    for c in range(len(request["cameras"])):
        model = mrcal.cameramodel(str(workdir / f"camera-{c}.cameramodel"))
        lensmodel, intrinsics = model.intrinsics()
        cameras.append({"lensmodel": lensmodel, "intrinsics": intrinsics.tolist(),
                        "rt_cam_ref": model.extrinsics_rt_fromref().tolist()})
    report = [line for line in done.stdout.splitlines()
              if line.startswith(("RMS", "Worst", "Noutliers", "calobject_warp"))]
    return {"cameras": cameras, "report": report}


def main() -> None:
    request = json.load(sys.stdin)
    with tempfile.TemporaryDirectory() as tmp:
        try:
            answer = solve(request, Path(tmp))
        except (OSError, ValueError, KeyError) as err:
            answer = {"error": f"{type(err).__name__}: {err}"}
    json.dump(answer, sys.stdout)


if __name__ == "__main__":
    main()
