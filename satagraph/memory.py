r"""Process-wide allocator settings for CPU work on large tensors.

torch's CPU allocator hands every large tensor to glibc ``malloc``, which
serves blocks above 128 KiB with fresh ``mmap`` pages and gives freed memory
back to the system at once. Each batch of frame graphs (several MB of
indices and features) then pays one page fault per 4 KiB page on every
call; while a virtual machine was reclaiming memory eagerly this made
:func:`~satagraph.data.collate_clips` 3.7 times slower (and cost nothing
measurable when it was not). Keeping freed
memory in the process avoids it.
"""
from __future__ import annotations

import ctypes
import ctypes.util
import sys

_M_TRIM_THRESHOLD, _M_TOP_PAD, _M_MMAP_THRESHOLD = -1, -2, -3
_MMAP_THRESHOLD_MAX = 32 * 2 ** 20  # glibc's upper bound on 64-bit systems


def retain_freed_memory(trim_threshold: int = 2 ** 30,
                        top_pad: int = 256 * 2 ** 20) -> bool:
    r"""Makes glibc keep freed memory for reuse instead of returning it to
    the system (``mallopt``): blocks up to 32 MiB come from the heap, the heap
    is trimmed only when :obj:`trim_threshold` bytes are free at its top, and
    it grows :obj:`top_pad` bytes at a time.

    The process's resident memory then stays near its peak. Called by the
    ``satagraph`` command; call it yourself in scripts that build batches on
    a CPU.

    Args:
        trim_threshold (int, optional): Free bytes at the heap's top before
            it is given back.
        top_pad (int, optional): Extra bytes asked for each time the heap
            grows.

    Returns:
        bool: Whether the settings took effect (``False`` off glibc).
    """
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        mallopt = libc.mallopt
    except (OSError, AttributeError):  # musl and other libcs
        return False
    mallopt.argtypes, mallopt.restype = [ctypes.c_int, ctypes.c_int], ctypes.c_int
    ok = [mallopt(_M_MMAP_THRESHOLD, _MMAP_THRESHOLD_MAX),
          mallopt(_M_TRIM_THRESHOLD, int(trim_threshold)),
          mallopt(_M_TOP_PAD, int(top_pad))]
    return all(result == 1 for result in ok)
