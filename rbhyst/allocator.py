"""The memory allocator of a process that is rbhyst's own (the command, a sweep's worker).

A run allocates and frees arrays of a few megabytes, and an estimate or a sweep's next case
allocates the same again. glibc's malloc maps each such array afresh and returns it to the
system when it is freed, so that the first touch of every page of every array costs a fault:
a third of an 8 s case of the seed deck in a sweep (14.8 -> 10.7 ms), 10 ms of the seed deck's
error estimate in the command (33 -> 24 ms). Raising the thresholds keeps freed memory in the
heap for the next array: the process's memory stays at its peak, never growing with the
cases. And one heap for every thread: glibc gives a thread an arena of its own, whose freed
memory no other thread reuses, so that what the threads formatting time_history.csv freed was
lost to the error estimate after them (the seed deck's estimate in the command took 30 ms, 25
with one heap).
Not set in a process that merely imports rbhyst (a notebook keeps its own allocator).
"""

from __future__ import annotations

#: arrays below this come from the heap, not from fresh mappings of their own
MMAP_THRESHOLD = 64 << 20
#: and the heap keeps this much freed memory before it gives any back
TRIM_THRESHOLD = 256 << 20


def keep_freed_memory() -> None:
    """Let glibc's malloc reuse freed memory (elsewhere nothing)."""
    try:
        import ctypes

        libc = ctypes.CDLL(None)
        libc.mallopt(-3, MMAP_THRESHOLD)  # M_MMAP_THRESHOLD
        libc.mallopt(-1, TRIM_THRESHOLD)  # M_TRIM_THRESHOLD
        libc.mallopt(-8, 1)  # M_ARENA_MAX
    except (OSError, AttributeError):  # pragma: no cover - not glibc
        pass
