"""What ``camlog calibrate`` writes besides the log: YAML, INI, JSON, Markdown and figures."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

import cv2
import numpy as np

from processors.calibration.board import Board
from processors.calibration.figures import (
    coverage_figure,
    rectified_pair_figure,
    residual_figure,
    view_error_figure,
)
from processors.calibration.solve import CalibrationOptions, MonoResult, max_projection_difference
from processors.calibration.stereo import StereoResult
from replay.calibration_ini import ost_text
from replay.calibration_yaml import calibration_to_yaml
from replay.formats import LogReader

if TYPE_CHECKING:
    from .flow import CameraStream


def _parameter_table(camera: CameraStream) -> dict[str, dict[str, float]]:
    result = camera.result
    assert result is not None
    truth = camera.truth
    true_values: dict[str, float] = {}
    if truth is not None:
        k = np.array(truth["k"])
        true_values = {"fx": k[0, 0], "fy": k[1, 1], "cx": k[0, 2], "cy": k[1, 2]}
        names = ["k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"]
        d = list(truth["d"]) + [0.0] * 8
        true_values |= dict(zip(names, d, strict=False))
    table = {}
    for name, value in result.parameters().items():
        row = {"value": float(value), "std": float(result.std.get(name, 0.0))}
        if name in true_values:
            row["truth"] = float(true_values[name])
            row["error"] = float(value - true_values[name])
        table[name] = row
    return table


def build_summary(cameras: list[CameraStream], stereo: StereoResult | None,
                  truth: dict[str, Any] | None, board: Board,
                  options: CalibrationOptions, *,
                  stereo_rejected: list[tuple[tuple[int, int], str]] | None = None
                  ) -> dict[str, Any]:
    """Machine-readable results (also stored in calibration.mcap and calibration.json).

    ``stereo_rejected`` lists the joint views (left frame, right frame) the stereo solve left
    out, and why."""
    from .flow import truth_model

    out: dict[str, Any] = {
        "board": {"pattern": board.pattern, "cols": board.cols, "rows": board.rows,
                  "square_m": board.square_m},
        "options": {"fix_principal_point": options.fix_principal_point,
                    "fix_aspect_ratio": options.fix_aspect_ratio,
                    "tangential": options.tangential,
                    "k_coefficients": options.k_coefficients,
                    "distortion_model": options.distortion_model},
        "cameras": [],
        "ground_truth": truth is not None,
    }
    for camera in cameras:
        result = camera.result
        assert result is not None and camera.size is not None and camera.coverage is not None
        distinct = [f for f in camera.frames if not f.duplicate]
        rejected = []
        for f in distinct:
            if f.detection is not None and not f.detection.accepted:
                rejected.append({"stamp_ns": f.stamp_ns, "reason": f.detection.reason})
            elif f.reason:
                rejected.append({"stamp_ns": f.stamp_ns, "reason": f.reason})
        for index, why in sorted(result.rejected.items()):
            rejected.append({"stamp_ns": camera.frames[index].stamp_ns, "reason": why})
        entry: dict[str, Any] = {
            "namespace": camera.namespace, "image_topic": camera.image_topic,
            "width": camera.size[0], "height": camera.size[1],
            "frames": len(camera.frames), "distinct_frames": len(distinct),
            "boards_found": sum(f.detection is not None for f in distinct),
            "candidate_views": len(camera.candidates), "selected_views": len(camera.selected),
            "used_views": len(result.view_ids), "rejected": rejected,
            "rms_px": result.rms_px, "distortion_model": result.model.distortion_model,
            "parameters": _parameter_table(camera),
            "cross_validation_px": camera.cross_validation_px,
            "tangential": _tangential_entry(result),
            "coverage": {name: {"min": lo, "max": hi, "progress": p}
                         for name, (lo, hi, p) in camera.coverage.ranges.items()}
            | {"image_cells": camera.coverage.image_cells},
        }
        if camera.truth is not None:
            seen = np.concatenate([camera.frames[i].detection.corners_px  # type: ignore[union-attr]
                                   for i in result.view_ids])
            true_model = truth_model(camera.truth)
            for key, within in (("", None), ("_covered", seen)):
                entry[f"max_projection_difference_vs_truth{key}_px"] = \
                    max_projection_difference(result.model, true_model, within=within)
                entry[f"max_projection_difference_vs_truth{key}_aligned_px"] = \
                    max_projection_difference(result.model, true_model, within=within,
                                              align_rotation=True)
        out["cameras"].append(entry)
    if stereo is not None:
        t = stereo.right_from_left[:3, 3]
        entry = {
            "rms_px": stereo.rms_px, "epipolar_rms_px": stereo.epipolar_rms_px,
            "baseline_m": stereo.baseline_m, "baseline_std_m": stereo.baseline_std_m,
            "square_m": stereo.square_m, "rotation_deg": stereo.rotation_deg,
            "translation_m": t.tolist(), "joint_views": len(stereo.view_epipolar_px),
            "rejected": [{"left_stamp_ns": cameras[0].frames[li].stamp_ns,
                          "right_stamp_ns": cameras[1].frames[ri].stamp_ns, "reason": why}
                         for (li, ri), why in stereo_rejected or []],
        }
        left, right = (truth_for_stereo(cameras[0]), truth_for_stereo(cameras[1]))
        if left is not None and right is not None:
            right_from_left = np.linalg.inv(right) @ left
            true_baseline = float(np.linalg.norm(right_from_left[:3, 3]))
            entry["truth"] = {"baseline_m": true_baseline,
                              "baseline_error_percent":
                                  100 * (stereo.baseline_m - true_baseline) / true_baseline}
        out["stereo"] = entry
    return out


def _tangential_entry(result: MonoResult) -> dict[str, Any]:
    """Whether p1, p2 were estimated, and the test that decided it (``tangential="auto"``)."""
    entry: dict[str, Any] = {"estimated": result.options.tangential == "estimate"}
    test = result.tangential_test
    if test is not None:
        entry |= {"chi2": test.chi2, "p_value": test.p_value, "summary": test.describe()}
    return entry


def truth_for_stereo(camera: CameraStream) -> np.ndarray | None:
    """``world_from_camera`` (4, 4) of a simulated camera."""
    if camera.truth is None:
        return None
    return np.array(camera.truth["world_from_camera"])


def _fmt(value: float) -> str:
    return f"{value:.6g}"


def markdown_report(summary: dict[str, Any], figures: list[str]) -> str:
    """A short human summary of the calibration."""
    board = summary["board"]
    flags = ", ".join(k.replace("_", "-") for k, v in summary["options"].items() if v is True)
    lines = [
        "# Calibration report", "",
        f"Board: {board['cols']}x{board['rows']} inner corners, {board['square_m']:g} m squares. "
        f"Model: {summary['options']['distortion_model']} with "
        f"{summary['options']['k_coefficients']} radial coefficients; options: "
        f"{flags or 'none'}; tangential distortion: {summary['options']['tangential']}.", "",
    ]
    for camera in summary["cameras"]:
        lines += [
            f"## {camera['namespace']}", "",
            f"{camera['frames']} frames ({camera['distinct_frames']} distinct), board found in "
            f"{camera['boards_found']}, {camera['candidate_views']} candidate views, "
            f"{camera['selected_views']} selected, {camera['used_views']} used. "
            f"Reprojection RMS {camera['rms_px']:.4f} px.", "",
        ]
        has_truth = any("truth" in row for row in camera["parameters"].values())
        header = "| parameter | value | σ | 3σ interval |" + (" truth | error | error/σ |"
                                                             if has_truth else "")
        lines += [header, "|" + " --- |" * (header.count("|") - 1)]
        for name, row in camera["parameters"].items():
            if row["std"] == 0:
                line = f"| {name} | {_fmt(row['value'])} | fixed | |"
                if has_truth and "truth" in row:
                    line += f" {_fmt(row['truth'])} | {row['error']:+.4g} | |"
                lines.append(line)
                continue
            lo, hi = row["value"] - 3 * row["std"], row["value"] + 3 * row["std"]
            line = f"| {name} | {_fmt(row['value'])} | {_fmt(row['std'])} | " \
                   f"[{_fmt(lo)}, {_fmt(hi)}] |"
            if has_truth and "truth" in row:
                ratio = abs(row["error"]) / row["std"] if row["std"] > 0 else float("inf")
                line += f" {_fmt(row['truth'])} | {row['error']:+.4g} | {ratio:.2f} |"
            lines.append(line)
        lines.append("")
        if "summary" in camera["tangential"]:
            lines.append(camera["tangential"]["summary"][0].upper()
                         + camera["tangential"]["summary"][1:] + ".")
        if camera.get("cross_validation_px") is not None:
            lines.append(f"Cross-validation: two disjoint halves of the views, calibrated "
                         f"separately, differ by at most {camera['cross_validation_px']:.3f} px "
                         "over the image once their camera frames are aligned.")
        if "max_projection_difference_vs_truth_px" in camera:
            lines.append(
                "Against the simulator's true model, max projection difference: "
                f"{camera['max_projection_difference_vs_truth_covered_aligned_px']:.3f} px "
                "where the views put corners and "
                f"{camera['max_projection_difference_vs_truth_aligned_px']:.3f} px over the "
                "whole image (its corners are extrapolated), after the best rotation of the "
                "camera frame, which intrinsic calibration cannot observe; without it "
                f"{camera['max_projection_difference_vs_truth_covered_px']:.3f} px and "
                f"{camera['max_projection_difference_vs_truth_px']:.3f} px.")
        cov = camera["coverage"]
        lines.append("Coverage: " + ", ".join(
            f"{k} {100 * v['progress']:.0f}%" for k, v in cov.items() if isinstance(v, dict))
            + f", image cells {100 * cov['image_cells']:.0f}%.")
        if camera["rejected"]:
            lines += ["", f"Rejected views ({len(camera['rejected'])}):"]
            reasons: dict[str, int] = {}
            for item in camera["rejected"]:
                key = item["reason"].split(" (")[0] if "RMS" not in item["reason"] \
                    else item["reason"]
                reasons[key] = reasons.get(key, 0) + 1
            lines += [f"- {count}× {reason}" for reason, count in reasons.items()]
        lines.append("")
    if "stereo" in summary:
        s = summary["stereo"]
        lines += [
            "## Stereo", "",
            f"{s['joint_views']} joint views. Stereo RMS {s['rms_px']:.4f} px, epipolar RMS "
            f"after rectification {s['epipolar_rms_px']:.4f} px.",
            f"Baseline {s['baseline_m']:.6f} m (σ {s['baseline_std_m']:.2g} m), rotation "
            f"{s['rotation_deg']:.4f}°, T = [{', '.join(f'{v:.5f}' for v in s['translation_m'])}]"
            " m.",
            f"Board square re-estimated by triangulation: {s['square_m']:.5f} m.",
        ]
        if s["rejected"]:
            lines.append(f"Rejected joint views ({len(s['rejected'])}):")
            lines += [f"- left {r['left_stamp_ns']} ns, right {r['right_stamp_ns']} ns: "
                      f"{r['reason']}" for r in s["rejected"]]
        if "truth" in s:
            lines.append(f"True baseline {s['truth']['baseline_m']:.6f} m: error "
                         f"{s['truth']['baseline_error_percent']:+.3f} %.")
        lines.append("")
    lines += ["## Figures", ""] + [f"![{name}]({name})" for name in figures] + [""]
    return "\n".join(lines)


def _image_at(reader: LogReader, topic: str, stamp_ns: int) -> np.ndarray | None:
    from .flow import _as_image, _bgr

    for raw in reader.raw_messages([topic]):
        image = _as_image(reader.decode(raw), reader, topic)
        if image.stamp_ns == stamp_ns:
            return _bgr(image)
    return None


def write_files(folder: Path, cameras: list[CameraStream], *, stereo: StereoResult | None,
                pairs: list[tuple[int, int]], summary: dict[str, Any], board: Board,
                camera_name: str | None, reader: LogReader) -> None:
    """Calibration files, JSON summary, figures and the Markdown report into ``folder``."""
    figures: list[str] = []
    for camera in cameras:
        info = camera.camera_info
        assert info is not None and camera.result is not None and camera.size is not None
        stereo_name = "left" if camera is cameras[0] else "right"
        yaml_name = "ost.yaml" if stereo is None else f"{stereo_name}.yaml"
        name = camera_name or camera.name
        if stereo is not None:
            name = f"{camera_name}/{stereo_name}" if camera_name else camera.name
        (folder / yaml_name).write_text(calibration_to_yaml(info, camera_name=name))
        prefix = "" if stereo is None else f"{stereo_name}_"
        result = camera.result
        used = [camera.frames[i].detection.corners_px for i in result.view_ids]  # type: ignore[union-attr]
        rejected_corners = [f.detection.corners_px for f in camera.frames
                            if not f.duplicate and f.detection is not None
                            and (not f.detection.accepted or f.reason
                                 or f.index in result.rejected)]
        assert camera.coverage is not None
        title = f"{camera.namespace}: {len(used)} views used, {len(rejected_corners)} rejected"
        cv2.imwrite(str(folder / f"{prefix}coverage.png"),
                    coverage_figure(camera.size, used, rejected_corners, title,
                                    camera.coverage.bars()))
        order = sorted({*result.view_rms_px, *result.rejected})
        errors = [result.view_rms_px.get(i, 0.0) for i in order]
        bad = [i in result.rejected for i in order]
        from .flow import outlier_limit

        cv2.imwrite(str(folder / f"{prefix}view_errors.png"),
                    view_error_figure(errors, bad, outlier_limit(camera),
                                      f"{camera.namespace}: per-view reprojection error"))
        cv2.imwrite(str(folder / f"{prefix}residuals.png"),
                    residual_figure(camera.size, used,
                                    [result.residuals_px[i] for i in result.view_ids],
                                    f"{camera.namespace}: residuals (observed - projected)"))
        figures += [f"{prefix}coverage.png", f"{prefix}view_errors.png",
                    f"{prefix}residuals.png"]
    if stereo is not None:
        left, right = cameras
        assert left.camera_info is not None and right.camera_info is not None
        (folder / "ost.txt").write_text(ost_text(left=left.camera_info,
                                                 right=right.camera_info))
        if pairs:
            li, ri = pairs[len(pairs) // 2]
            images = [_image_at(reader, c.image_topic, c.frames[i].stamp_ns)
                      for c, i in ((left, li), (right, ri))]
            if images[0] is not None and images[1] is not None:
                rectified = []
                for camera, image in zip(cameras, images, strict=True):
                    info = camera.camera_info
                    assert info is not None and camera.size is not None and image is not None
                    maps = cv2.initUndistortRectifyMap(info.k, info.d, info.r, info.p[:, :3],
                                                       camera.size, cv2.CV_16SC2)
                    rectified.append(cv2.remap(image, maps[0], maps[1], cv2.INTER_LINEAR))
                cv2.imwrite(str(folder / "rectified.png"), rectified_pair_figure(
                    rectified[0], rectified[1],
                    f"rectified pair: epipolar RMS {stereo.epipolar_rms_px:.3f} px"))
                figures.append("rectified.png")
    else:
        assert cameras[0].camera_info is not None
        (folder / "ost.txt").write_text(ost_text(cameras[0].camera_info))
    (folder / "calibration.json").write_text(json.dumps(summary, indent=1) + "\n")
    (folder / "report.md").write_text(markdown_report(summary, figures))
