"""Report figures drawn with OpenCV: coverage, per-view error, residuals, rectified pairs.

Each function returns a BGR image ``(H, W, 3)`` uint8 ready for ``cv2.imwrite``.
"""

from __future__ import annotations

import cv2
import numpy as np

from replay.messages import F64

FONT = cv2.FONT_HERSHEY_SIMPLEX
GREEN, RED, GREY, BLUE, BLACK, ORANGE = (60, 160, 60), (40, 40, 210), (170, 170, 170), \
    (200, 120, 40), (30, 30, 30), (30, 140, 240)


def _canvas(width: int, height: int, margin: int = 40) -> tuple[np.ndarray, int]:
    return np.full((height + 2 * margin, width + 2 * margin, 3), 255, np.uint8), margin


def _text(img: np.ndarray, text: str, org: tuple[int, int], scale: float = 0.5,
          color: tuple[int, int, int] = BLACK) -> None:
    cv2.putText(img, text, org, FONT, scale, color, 1, cv2.LINE_AA)


def _hue(i: int, n: int) -> tuple[int, int, int]:
    hsv = np.array([[[int(170 * i / max(1, n - 1)), 200, 200]]], dtype=np.uint8)
    b, g, r = cv2.cvtColor(hsv, cv2.COLOR_HSV2BGR)[0, 0]
    return int(b), int(g), int(r)


def coverage_figure(size: tuple[int, int], used: list[F64], rejected: list[F64],
                    title: str, bars: str) -> np.ndarray:
    """Corners of every used view (one colour each) and rejected views (red) over the image."""
    w, h = size
    img, m = _canvas(w, h)
    cv2.rectangle(img, (m, m), (m + w - 1, m + h - 1), BLACK, 1)
    for gx in range(1, 8):
        x = m + gx * w // 8
        cv2.line(img, (x, m), (x, m + h - 1), (235, 235, 235), 1)
    for gy in range(1, 6):
        y = m + gy * h // 6
        cv2.line(img, (m, y), (m + w - 1, y), (235, 235, 235), 1)
    for corners in rejected:
        pts = np.rint(corners + m).astype(np.int32)
        for p in pts:
            cv2.drawMarker(img, tuple(int(v) for v in p), RED, cv2.MARKER_TILTED_CROSS, 6, 1)
    for i, corners in enumerate(used):
        color = _hue(i, len(used))
        for p in np.rint(corners + m).astype(np.int32):
            cv2.circle(img, (int(p[0]), int(p[1])), 2, color, -1, cv2.LINE_AA)
    _text(img, title, (m, 25), 0.6)
    lines = bars.splitlines()
    out = np.full((img.shape[0] + 18 * len(lines) + 10, img.shape[1], 3), 255, np.uint8)
    out[: img.shape[0]] = img
    for i, line in enumerate(lines):
        _text(out, line, (m, img.shape[0] + 14 + 18 * i), 0.45)
    return out


def view_error_figure(errors_px: list[float], rejected: list[bool], limit_px: float | None,
                      title: str) -> np.ndarray:
    """Bar chart of per-view RMS reprojection error; rejected views in red."""
    width, height, m = 900, 320, 50
    img = np.full((height + 2 * m, width + 2 * m, 3), 255, np.uint8)
    top = max([*errors_px, limit_px or 0.0, 1e-6]) * 1.15
    n = max(1, len(errors_px))
    bar = width / n
    for i, (e, bad) in enumerate(zip(errors_px, rejected, strict=True)):
        x0 = int(m + i * bar)
        x1 = max(x0 + 1, int(m + (i + 1) * bar) - 1)
        y = int(m + height - e / top * height)
        cv2.rectangle(img, (x0, y), (x1, m + height), RED if bad else GREEN, -1)
    cv2.line(img, (m, m + height), (m + width, m + height), BLACK, 1)
    cv2.line(img, (m, m), (m, m + height), BLACK, 1)
    kept = [e for e, bad in zip(errors_px, rejected, strict=True) if not bad]
    if kept:
        median = float(np.median(kept))
        y = int(m + height - median / top * height)
        cv2.line(img, (m, y), (m + width, y), BLUE, 1)
        _text(img, f"median {median:.3f} px", (m + width - 170, y - 5), 0.45, BLUE)
    if limit_px is not None:
        y = int(m + height - limit_px / top * height)
        cv2.line(img, (m, y), (m + width, y), RED, 1)
        _text(img, f"rejection limit {limit_px:.3f} px", (m + 5, y - 5), 0.45, RED)
    for frac in (0.0, 0.5, 1.0):
        y = int(m + height - frac * height)
        _text(img, f"{frac * top:.3f}", (2, y + 4), 0.4)
    _text(img, title, (m, 30), 0.6)
    _text(img, "views in time order (green: used, red: rejected); RMS reprojection error, px",
          (m, m + height + 30), 0.45)
    return img


def residual_figure(size: tuple[int, int], corners: list[F64], residuals: list[F64],
                    title: str) -> np.ndarray:
    """Residual vectors (observed - projected) at every used corner, magnified."""
    w, h = size
    img, m = _canvas(w, h)
    cv2.rectangle(img, (m, m), (m + w - 1, m + h - 1), BLACK, 1)
    all_res = np.concatenate(residuals) if residuals else np.zeros((1, 2))
    typical = float(np.percentile(np.linalg.norm(all_res, axis=1), 95)) or 1e-3
    scale = 12.0 / typical  # the 95th percentile residual draws 12 px long
    for c, r in zip(corners, residuals, strict=True):
        for p, d in zip(c, r, strict=True):
            start = (round(p[0] + m), round(p[1] + m))
            end = (round(p[0] + m + d[0] * scale), round(p[1] + m + d[1] * scale))
            color = RED if np.linalg.norm(d) > typical else ORANGE
            cv2.arrowedLine(img, start, end, color, 1, cv2.LINE_AA, tipLength=0.3)
    _text(img, title, (m, 25), 0.6)
    _text(img, f"arrows magnified x{scale:.0f}: 12 px = {typical:.3f} px residual "
          "(95th percentile)", (m, m + h + 25), 0.45)
    return img


def rectified_pair_figure(left_bgr: np.ndarray, right_bgr: np.ndarray, title: str,
                          lines: int = 16) -> np.ndarray:
    """Rectified left and right side by side with horizontal lines: rows must match."""
    h = left_bgr.shape[0]
    pair = np.concatenate([left_bgr, right_bgr], axis=1).copy()
    for i in range(1, lines):
        y = i * h // lines
        cv2.line(pair, (0, y), (pair.shape[1] - 1, y), (0, 200, 0), 1)
    out = np.full((pair.shape[0] + 40, pair.shape[1], 3), 255, np.uint8)
    out[40:] = pair
    _text(out, title, (10, 27), 0.6)
    return out


def annotate_detection(bgr: np.ndarray, corners_px: F64 | None, board_size: tuple[int, int],
                       status: str, used: bool) -> np.ndarray:
    """The frame with its corners drawn: OpenCV's rainbow when used, red crosses otherwise."""
    out = bgr.copy()
    if corners_px is not None and used and len(corners_px) != board_size[0] * board_size[1]:
        for p in np.rint(corners_px).astype(int):  # some corners of a ChArUco board
            cv2.circle(out, (int(p[0]), int(p[1])), 4, GREEN, 2, cv2.LINE_AA)
    elif corners_px is not None:
        if used:
            cv2.drawChessboardCorners(out, board_size,
                                      corners_px.reshape(-1, 1, 2).astype(np.float32), True)
        else:
            for p in np.rint(corners_px).astype(int):
                cv2.drawMarker(out, (int(p[0]), int(p[1])), RED, cv2.MARKER_TILTED_CROSS, 9, 2)
    color = GREEN if used else RED
    cv2.rectangle(out, (0, 0), (out.shape[1] - 1, 22), (255, 255, 255), -1)
    _text(out, status, (5, 16), 0.5, color)
    return out


#: contour levels (px) drawn on the uncertainty map, where they fall inside its range
UNCERTAINTY_LEVELS = (0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0)


def uncertainty_figure(size: tuple[int, int], grid_px: F64, sigma_px: F64, title: str,
                       seen_px: F64 | None = None) -> np.ndarray:
    """The projection uncertainty ``sigma_px`` ``(rows, cols)`` given at the grid pixels
    ``grid_px`` ``(rows, cols, 2)`` spread over the image, with contours at round values, a
    colour bar and, when given, the corners the views put on the image ``(N, 2)`` (grey)."""
    w, h = size
    rows, cols = sigma_px.shape
    # bilinear over the grid: image pixel (u, v) sits at grid position (u / du, v / dv)
    u, v = np.meshgrid(np.arange(w, dtype=np.float32), np.arange(h, dtype=np.float32))
    du = float(grid_px[0, -1, 0] - grid_px[0, 0, 0]) / max(cols - 1, 1)
    dv = float(grid_px[-1, 0, 1] - grid_px[0, 0, 1]) / max(rows - 1, 1)
    field = cv2.remap(np.nan_to_num(sigma_px, nan=float(np.nanmax(sigma_px))).astype(np.float32),
                      u / du, v / dv, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    top = float(np.nanmax(sigma_px)) or 1e-9
    colours = cv2.applyColorMap(np.clip(field / top * 255, 0, 255).astype(np.uint8),
                                cv2.COLORMAP_VIRIDIS)
    if seen_px is not None:
        for p in np.rint(seen_px[::max(1, len(seen_px) // 4000)]).astype(int):
            cv2.circle(colours, (int(p[0]), int(p[1])), 1, GREY, -1)
    for level in UNCERTAINTY_LEVELS:
        if not float(field.min()) < level < top:
            continue
        contours, _ = cv2.findContours((field >= level).astype(np.uint8), cv2.RETR_LIST,
                                       cv2.CHAIN_APPROX_SIMPLE)
        cv2.drawContours(colours, contours, -1, (255, 255, 255), 1, cv2.LINE_AA)
        if contours:
            longest = max(contours, key=len)
            x, y = longest[len(longest) // 2, 0]
            _text(colours, f"{level:g}", (int(x) + 3, int(y) - 3), 0.4, (255, 255, 255))
    img, m = _canvas(w + 90, h)
    img[m:m + h, m:m + w] = colours
    bar_x = m + w + 20
    values = ((1.0 - np.arange(h) / max(h - 1, 1)) * 255).astype(np.uint8)  # top: the largest
    img[m:m + h, bar_x:bar_x + 16] = cv2.applyColorMap(values[:, None], cv2.COLORMAP_VIRIDIS)
    for frac in (0.0, 0.5, 1.0):
        _text(img, f"{frac * top:.3g}", (bar_x + 20, m + int((1 - frac) * (h - 1)) + 4), 0.4)
    _text(img, "px", (bar_x, m - 8), 0.45)
    _text(img, title, (m, 25), 0.55)
    return img
