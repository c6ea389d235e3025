"""Where a camera frame's memory comes from: the C allocator's policy for big blocks (no Qt).

Decision: big blocks stay in the process
    A camera frame arrives as one bytes object of its size (921,600 bytes for 640x480 rgb8, 6.2 MB at
    1080p), lives a few milliseconds (decoded, recorded or dropped: latest wins) and is freed; the next
    frame asks for the same size again.  glibc's malloc serves a block of 128 kB or more with a fresh
    ``mmap`` and gives it back with ``munmap`` when it is freed (its threshold adapts upwards after a free,
    but the heap's top is then trimmed back to the OS past twice that threshold): every frame's pages are
    then faulted in and zeroed again by the kernel.  Measured with ``python benchmarks/bench_record.py
    --only ingest`` (640x480 rgb8 at 120 Hz; CPU over each process's steady window, 2-3 rounds): a plain
    subscriber that only counts the frames 1.58 ms of CPU a frame, 1.23 ms of it system time; with the
    policy below 0.43-0.46 ms (0.10-0.14 ms system time); ``rcon record`` 1.79 -> 1.14 ms a frame.

    :func:`keep_big_blocks` (called by the app's and the CLI's entry points, and by anything that wants the
    same) sets glibc's mmap threshold to :data:`MMAP_THRESHOLD` (a 1080p rgb8 frame is below it) and its
    trim threshold to :data:`TRIM_THRESHOLD`: blocks up to that size come from the heap and their pages are
    kept for the next frame.  What it costs: at most ``TRIM_THRESHOLD`` of freed memory kept by each malloc
    arena (a thread's), and only after the process held that much at once.  In the app it changes little:
    ``python benchmarks/bench_app.py --robots 3`` (6 cameras) gave app CPU 0.374-0.383 with it and
    0.374-0.378 without, peak RSS 209-215 MB either way, the sims' CPU 0.079-0.091 with and 0.088-0.098
    without (a busy process's fragmented heap mostly kept big blocks already).  Elsewhere (macOS,
    Windows, musl) nothing is changed: their allocators keep big blocks on their own terms.  Nothing here
    raises.
"""

from __future__ import annotations

import contextlib
import ctypes
import logging
import platform
import sys

log = logging.getLogger(__name__)

#: glibc's ``M_TRIM_THRESHOLD`` and ``M_MMAP_THRESHOLD`` (malloc.h)
_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3
#: blocks smaller than this come from the heap (bytes; glibc's default adapts from 128 kB up to 32 MB)
MMAP_THRESHOLD = 16 << 20
#: freed memory at the top of a heap kept for the next block before it is given back (bytes)
TRIM_THRESHOLD = 32 << 20

_applied: list[bool] = []


def keep_big_blocks() -> bool:
    """Apply the policy (see the module docstring) once per process; True when glibc took it."""
    if _applied:
        return _applied[0]
    ok = False
    if sys.platform.startswith("linux") and platform.libc_ver()[0] == "glibc":
        with contextlib.suppress(OSError, AttributeError):
            libc = ctypes.CDLL(None)
            ok = bool(libc.mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD)) and bool(
                libc.mallopt(_M_TRIM_THRESHOLD, TRIM_THRESHOLD))
        if not ok:
            log.debug("glibc did not take the big-block policy")
    _applied.append(ok)
    return ok
