"""RVL, the lossless depth codec of compressed_depth_image_transport (Wilson, "Fast Lossless
Depth Image Compression", 2017), decoded with numpy.

The stream is little-endian 32-bit words of eight 4-bit nibbles, the first nibble in the
top bits. A value is a run of nibbles, three bits each, least significant first, the top bit
of a nibble set when another follows. The values are, until every pixel is accounted for: a
count of zeros, a count of non-zero pixels, then that many zigzag-coded differences from the
previous non-zero pixel (the first from 0).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from ..errors import EncodingError

__all__ = ["decode_rvl"]


def _values(stream: bytes) -> npt.NDArray[np.int64]:
    """Every variable-length value of the stream, in order."""
    words = np.frombuffer(stream, "<u4", count=len(stream) // 4)
    shifts = np.arange(28, -1, -4, dtype=np.uint32)
    nibbles = ((words[:, None] >> shifts) & 0xF).astype(np.int64).reshape(-1)
    ends = np.flatnonzero(nibbles < 8)  # the last nibble of each value
    if ends.size == 0:
        return np.zeros(0, np.int64)
    starts = np.concatenate(([0], ends[:-1] + 1))
    used = nibbles[: ends[-1] + 1]
    place = np.arange(used.size) - np.repeat(starts, ends - starts + 1)
    if place.max() > 10:  # more than 30 bits: no count or difference of 16-bit pixels
        raise EncodingError("RVL stream holds a value too long for 16-bit depth")
    result: npt.NDArray[np.int64] = np.add.reduceat((used & 7) << (3 * place), starts)
    return result


def _ranges(starts: list[int], lengths: list[int]) -> npt.NDArray[np.int64]:
    """The indices ``start .. start + length - 1`` of every range, concatenated."""
    lengths_arr = np.asarray(lengths, np.int64)
    total = int(lengths_arr.sum())
    offsets = np.repeat(np.asarray(starts, np.int64) - (np.cumsum(lengths_arr) - lengths_arr),
                        lengths_arr)
    result: npt.NDArray[np.int64] = offsets + np.arange(total, dtype=np.int64)
    return result


def decode_rvl(stream: bytes, width: int, height: int) -> npt.NDArray[np.uint16]:
    """The ``(height, width)`` uint16 image of an RVL stream."""
    values = _values(stream)
    listed: list[Any] = values.tolist()
    pixels = width * height
    runs: list[int] = []  # first pixel of each run of non-zero pixels
    firsts: list[int] = []  # index in ``values`` of its first difference
    lengths: list[int] = []
    done = index = 0
    while done < pixels:
        if index + 1 >= len(listed):
            raise EncodingError(f"RVL stream ends after {done} of {pixels} pixels")
        zeros, nonzeros = listed[index], listed[index + 1]
        done += zeros
        if nonzeros:
            runs.append(done)
            firsts.append(index + 2)
            lengths.append(nonzeros)
        done += nonzeros
        index += 2 + nonzeros
    if done != pixels or index > len(listed):
        raise EncodingError(f"RVL stream holds {done} pixels, not {width}x{height}")
    image = np.zeros(pixels, np.uint16)
    if runs:
        zigzag = values[_ranges(firsts, lengths)]
        differences = (zigzag >> 1) ^ -(zigzag & 1)
        image[_ranges(runs, lengths)] = np.cumsum(differences) & 0xFFFF
    return image.reshape(height, width)
