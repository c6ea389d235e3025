"""The allocator policy for camera-frame-sized blocks (``rcon_core/mallocpolicy.py``): with it, a frame's
pages are not faulted in again for every frame (glibc on Linux; elsewhere it changes nothing)."""

from __future__ import annotations

import platform
import subprocess
import sys

import pytest

pytestmark = pytest.mark.skipif(not (sys.platform.startswith("linux") and platform.libc_ver()[0] == "glibc"),
                                reason="the policy is glibc's; other allocators are left as they are")

FRAMES = """
import resource, sys
if sys.argv[1] == "policy":
    from rcon_core.mallocpolicy import keep_big_blocks
    assert keep_big_blocks() and keep_big_blocks()  # taken, and a second call is harmless
else:  # glibc's starting thresholds, held (left to adapt, they depend on what the process did before)
    import ctypes
    libc = ctypes.CDLL(None)
    assert libc.mallopt(-3, 128 * 1024) and libc.mallopt(-1, 128 * 1024)
keep = []
def frame(i):  # what a camera stream does: the frame as read, the payload taken out of it, a copy
    read = bytes([i % 256]) * 921_700
    payload = read[100:]
    copy = bytearray(payload)
    keep.append(bytes(1000 + i % 7))
    del keep[:-3]
    return len(read) + len(payload) + len(copy)
for i in range(50):  # warm: the allocator has seen the sizes
    frame(i)
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for i in range(200):
    frame(i)
print((resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before) / 200)
"""


def faults_per_frame(mode: str) -> float:
    out = subprocess.run([sys.executable, "-c", FRAMES, mode], capture_output=True, text=True, check=True)
    return float(out.stdout.strip())


def test_a_frame_sized_block_is_not_faulted_in_again_for_every_frame() -> None:
    without, with_policy = faults_per_frame("default"), faults_per_frame("policy")
    # the three frame-sized blocks are 675 pages: without the policy they are faulted in again each frame
    assert without > 100, without
    assert with_policy < 5, with_policy


def test_the_entry_points_apply_it() -> None:
    """The app, `rcon sim` and `rcon record` call it (a process that streams frames gets the policy)."""
    from pathlib import Path

    import rcon_core

    root = Path(rcon_core.__file__).parent
    for module in ("app/main.py", "cli/sim_cmd.py", "cli/record_cmd.py"):
        assert "keep_big_blocks()" in (root / module).read_text(), module
