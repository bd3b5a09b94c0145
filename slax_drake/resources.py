"""Memory budget of a request: a size or resolution argument is refused up front, with its estimate, when the
arrays it implies would not fit in this machine's available memory (instead of growing until the kernel's
out-of-memory killer ends the process).

Estimates are of the large arrays only (a few hundred MB of interpreter, libraries and Drake come on top); each
stage computes its own next to the code that allocates (``occupancy_memory_bytes``, ``dataset_memory_bytes``,
``training_memory_bytes``, ...), and :func:`check_memory` compares it with :func:`available_memory_bytes`.
"""

from __future__ import annotations

import os

from slax_drake.errors import MemoryBudgetError

GB = 1e9


def available_memory_bytes() -> int:
    """Memory available to a new allocation now (Linux ``MemAvailable``; elsewhere the physical memory)."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")


def check_memory(estimate_bytes: float, request: str, advice: str, available: int | None = None) -> None:
    """Raises MemoryBudgetError when ``estimate_bytes`` exceeds the available memory; ``request`` names what
    asks for it (e.g. "--grid-step 1e-05"), ``advice`` says what to change."""
    available = available_memory_bytes() if available is None else available
    if estimate_bytes > available:
        raise MemoryBudgetError(
            f"{request} needs about {format_bytes(estimate_bytes)} of memory, more than the "
            f"{format_bytes(available)} available; {advice}"
        )


def format_bytes(n: float) -> str:
    """``n`` bytes as "1.5 GB" / "320 MB" (decimal units)."""
    if n >= 1e15:
        return f"{n / 1e12:,.0f} TB"
    if n >= 1e12:
        return f"{n / 1e12:.3g} TB"
    if n >= GB:
        return f"{n / GB:.3g} GB"
    return f"{n / 1e6:.3g} MB"
