"""The C heap of a command's process: freed large blocks kept for reuse (glibc's ``mallopt``).

A design's solver makes and frees large temporaries on every step at 64x64 tiles and up (the regulariser's
sparse Jacobian and its coordinate slices, the products of the grid block, the deployed nodes' arrays). glibc
serves a block above its mmap threshold from fresh pages and unmaps it when freed, and trims the freed top of
the heap, so every step pays the kernel's page faults for the same sizes again: system time that grows with
the lattice (docs/speed.md, "the C heap"). Raising both thresholds keeps those blocks in the heap, where
the next step's arrays reuse them. The arithmetic is untouched: the same designs, bit for bit.
"""

from __future__ import annotations

import sys

# glibc's mallopt parameters (malloc.h)
M_TRIM_THRESHOLD = -1
M_MMAP_THRESHOLD = -3
# blocks up to this size come from the heap, and up to this much freed top of the heap is kept
KEEP_BYTES = 1 << 30

# commands whose solver steps make and free large arrays
KEEP_FREED = ("design",)


def keep_freed_memory(command: str | None) -> bool:
    """For a command in ``KEEP_FREED`` on glibc, keep freed blocks in the heap for reuse (both thresholds at
    ``KEEP_BYTES``); returns whether it did. Only the CLI's own process calls it (a library caller's heap
    is its own)."""
    if command not in KEEP_FREED or not sys.platform.startswith("linux"):
        return False
    import ctypes  # here: ``fabkiri --help`` loads none of this

    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):  # pragma: no cover - a libc without mallopt
        return False
    mallopt.argtypes = (ctypes.c_int, ctypes.c_int)
    mallopt.restype = ctypes.c_int
    return bool(mallopt(M_MMAP_THRESHOLD, KEEP_BYTES)) and bool(
        mallopt(M_TRIM_THRESHOLD, KEEP_BYTES)
    )
