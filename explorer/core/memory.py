"""How much memory a plan may take, and how its size is shown.

A plan (a sweep's table of runs, a grid) is refused before any allocation when it would not fit
in the memory this process can still get: the smaller of the machine's available memory
(/proc/meminfo MemAvailable: free plus reclaimable caches) and what the process's control group
still allows (cgroup v2 memory.max - memory.current, or v1's limit - usage). numpy would
otherwise try to allocate terabytes and end in a MemoryError traceback, or the kernel's OOM
killer would end the process, or another one, much later.
"""

from __future__ import annotations

import os
from pathlib import Path

UNKNOWN = 1 << 62  # no limit found: every plan passes this check (the others still apply)


def _read_int(path: str) -> int | None:
    try:
        text = Path(path).read_text().split()[0]
    except (OSError, IndexError):
        return None
    return int(text) if text.isdigit() else None


def _meminfo_available() -> int | None:
    try:
        with open("/proc/meminfo") as handle:
            for line in handle:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        return None
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return None


def _cgroup_room() -> int | None:
    limit, used = _read_int("/sys/fs/cgroup/memory.max"), _read_int("/sys/fs/cgroup/memory.current")
    if limit is None:  # cgroup v1
        limit = _read_int("/sys/fs/cgroup/memory/memory.limit_in_bytes")
        used = _read_int("/sys/fs/cgroup/memory/memory.usage_in_bytes")
    if limit is None or limit >= 1 << 60:  # "max", or v1's page-rounded 2**63
        return None
    return max(0, limit - (used or 0))


def available_bytes() -> int:
    """Bytes this process can still allocate, as far as the system tells (UNKNOWN if it does not)."""
    known = [v for v in (_meminfo_available(), _cgroup_room()) if v is not None]
    return min(known) if known else UNKNOWN


def size_text(n: float) -> str:
    """Bytes in binary units, 3 significant digits: '14.6 TiB'."""
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"):
        if abs(n) < 1024.0 or unit == "EiB":
            return f"{n:.3g} {unit}" if unit != "B" else f"{int(n)} B"
        n /= 1024.0
    return f"{n:.3g} EiB"
