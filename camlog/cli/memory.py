"""Freed buffers kept for reuse: glibc's thresholds raised for a process that streams images.

Decompressed chunks, images and output chunks of a few MB are allocated and freed with every
message. By default glibc gives freed heap back to the kernel as soon as more than its trim
threshold (twice the largest block freed so far) lies free at the top, and serves blocks
above its mmap threshold with fresh pages, so the next message page-faults its memory anew:
1.5 s of system time, a fifth of the CPU time, in calibrating a 60 s log. With both raised
the freed blocks are reused; a run holds a bounded number of them at a time.
"""

from __future__ import annotations

__all__ = ["keep_freed_memory"]

#: glibc's mallopt parameter numbers (malloc.h)
M_TRIM_THRESHOLD, M_MMAP_THRESHOLD = -1, -3
#: blocks up to this size come from the heap (glibc's own ceiling: 32 MiB on 64 bits)
MMAP_THRESHOLD_BYTES = 32 * 1024 * 1024
#: free memory at the heap's top kept for reuse
TRIM_THRESHOLD_BYTES = 256 * 1024 * 1024


def keep_freed_memory() -> bool:
    """Raise glibc's mmap and trim thresholds for this process; False where the C library
    is not glibc (nothing changed)."""
    import ctypes

    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError, TypeError):  # not a glibc-like libc, or no handle
        return False
    mallopt.argtypes = [ctypes.c_int, ctypes.c_int]
    return bool(mallopt(M_MMAP_THRESHOLD, MMAP_THRESHOLD_BYTES)) and \
        bool(mallopt(M_TRIM_THRESHOLD, TRIM_THRESHOLD_BYTES))
