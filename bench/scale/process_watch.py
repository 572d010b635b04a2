"""CPU time and resident memory of one process, from /proc (Linux)."""

from __future__ import annotations

import os
import time
from pathlib import Path


class ProcessWatch:
    """CPU time and resident memory of one process, from /proc (Linux)."""

    def __init__(self, pid: int) -> None:
        self.pid = pid
        self._ticks = os.sysconf("SC_CLK_TCK")
        self._last = (time.monotonic(), self._cpu_s())

    def cpu_seconds(self) -> float:
        return self._cpu_s()

    def _cpu_s(self) -> float:
        fields = Path(f"/proc/{self.pid}/stat").read_text().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / self._ticks  # utime + stime

    def cpu_percent(self) -> float:
        """% of one core since the last call."""
        now, cpu = time.monotonic(), self._cpu_s()
        then, before = self._last
        self._last = (now, cpu)
        return 100.0 * (cpu - before) / max(1e-9, now - then)

    def rss(self) -> int:
        for line in Path(f"/proc/{self.pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
        return 0
