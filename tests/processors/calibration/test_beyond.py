"""Where no board reached: the outline of the views' corners, the parts of the image beyond it
and the worst uncertainty there."""

from __future__ import annotations

import numpy as np

from processors.calibration.beyond import beyond_boards, parts, reached

SIZE = (300, 200)


def box(x0: float, y0: float, width: float, height: float) -> np.ndarray:
    u, v = np.meshgrid(np.linspace(x0, x0 + width, 5), np.linspace(y0, y0 + height, 5))
    return np.column_stack([u.ravel(), v.ravel()])


def test_the_outline_of_each_view_is_reached() -> None:
    mask = reached(SIZE, [box(100, 50, 100, 100), np.array([[5.0, 5.0], [6.0, 6.0]])])
    assert mask.shape == (200, 300)
    assert mask[100, 150] and mask[50, 100] and mask[150, 200]  # inside, on its corners
    assert not mask[10, 10] and not mask[190, 290]  # a view of two points has no outline
    assert mask[48, 150] and not mask[40, 150]  # a few pixels' margin


def test_the_parts_are_named_by_thirds() -> None:
    corners = np.array([[5.0, 5.0], [295.0, 195.0]])
    assert parts(corners, SIZE) == "corners of the image"
    assert parts(np.vstack([corners, [[5.0, 100.0]]]), SIZE) == \
        "corners and left edge of the image"
    edges = np.array([[150.0, 5.0], [150.0, 195.0], [5.0, 100.0], [295.0, 100.0]])
    assert parts(edges, SIZE) == "edges of the image"
    assert parts(np.zeros((0, 2)), SIZE) == ""


def test_the_worst_uncertainty_beyond_the_boards() -> None:
    u, v = np.meshgrid(np.linspace(0, 299, 7), np.linspace(0, 199, 5))
    pixels = np.stack([u, v], axis=2)
    sigma = 0.01 + np.hypot(pixels[..., 0] - 150, pixels[..., 1] - 100) / 1000
    sigma[0, 0] = np.nan  # no figure: neither counted nor shared
    beyond = beyond_boards(pixels, sigma, reached(SIZE, [box(60, 40, 180, 120)]))
    assert beyond is not None
    assert beyond.worst_px == np.nanmax(sigma)
    assert beyond.where == "corners and edges of the image"
    outside = np.isfinite(sigma) & ((pixels[..., 0] < 56) | (pixels[..., 0] > 244)
                                    | (pixels[..., 1] < 36) | (pixels[..., 1] > 164))
    assert beyond.share == outside.sum() / np.isfinite(sigma).sum()
    everywhere = reached(SIZE, [np.array([[0.0, 0.0], [299.0, 0.0], [299.0, 199.0],
                                          [0.0, 199.0]])])
    assert beyond_boards(pixels, sigma, everywhere) is None
