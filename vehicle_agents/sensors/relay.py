"""From a scan source to the hub: stamp each turn with the flight controller's clock and
pose, pack it as a binary scan frame (protocol.scans), and keep it for the hub link.

Delivery: the newest scan goes first, never behind a backlog; scans the link could not
send (an outage) wait in a bounded budget (`ScanOutbox`, about 10 minutes at 10 Hz) and
follow oldest first, flagged as replayed, so the store gets them and live views do not.
A full budget drops its oldest scans and counts them. Scans have their own budget, apart
from the telemetry outbox: they never push out telemetry or events.
"""

from __future__ import annotations

import asyncio
import logging
import math
import sqlite3
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

from common.retry import Backoff, Retries
from protocol.messages import MAX_SOURCE_COUNTS, ScanSourceStats
from protocol.scans import FLAG_REPLAYED, Mount, ScanFrame, encode_scan, with_flags
from vehicle_agents.sensors.fcu_time import PoseHistory
from vehicle_agents.sensors.turn import ScanSource, Turn

log = logging.getLogger(__name__)

POSE_WAIT_S = 0.5  # how long a turn waits for the flight controller's pose to cover it
POSE_POLL_S = 0.01


class Backlog(Protocol):
    """Scans waiting for the hub, oldest first."""

    def __len__(self) -> int: ...

    def append(self, frame: bytes) -> None: ...

    def appendleft(self, frame: bytes) -> None: ...

    def popleft(self) -> bytes: ...


class DiskBacklog:
    """The backlog in a SQLite file: an outage's scans survive an agent restart too, and
    cost a drone's flash, not its memory. Written only while scans wait (an outage, a
    slow link); on a healthy link each scan is sent before the next one comes."""

    def __init__(self, path: Path) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        self._db = sqlite3.connect(path, isolation_level=None)
        self._db.execute("PRAGMA journal_mode=WAL")
        self._db.execute("PRAGMA synchronous=NORMAL")
        self._db.execute("CREATE TABLE IF NOT EXISTS scans (id INTEGER PRIMARY KEY, frame BLOB)")
        self._count = int(self._db.execute("SELECT count(*) FROM scans").fetchone()[0])

    def __len__(self) -> int:
        return self._count

    def append(self, frame: bytes) -> None:
        self._db.execute("INSERT INTO scans (frame) VALUES (?)", (frame,))
        self._count += 1

    def appendleft(self, frame: bytes) -> None:
        first = self._db.execute("SELECT coalesce(min(id), 1) FROM scans").fetchone()[0]
        self._db.execute("INSERT INTO scans (id, frame) VALUES (?, ?)", (first - 1, frame))
        self._count += 1

    def popleft(self) -> bytes:
        row = self._db.execute("SELECT id, frame FROM scans ORDER BY id LIMIT 1").fetchone()
        if row is None:
            raise IndexError("empty backlog")
        self._db.execute("DELETE FROM scans WHERE id = ?", (row[0],))
        self._count -= 1
        return bytes(row[1])


class ScanOutbox:
    """The newest scan, and a bounded backlog of older unsent ones (in memory, or on
    disk with `DiskBacklog`)."""

    def __init__(self, budget: int, backlog: Backlog | None = None) -> None:
        self.budget = budget
        self._latest: bytes | None = None
        self._backlog: Backlog = backlog if backlog is not None else deque()
        self._ready = asyncio.Event()
        if len(self._backlog):
            self._ready.set()  # an earlier run's scans, kept on disk
        self.dropped = 0
        self.sent = 0

    def __len__(self) -> int:
        return len(self._backlog) + (self._latest is not None)

    def put(self, frame: bytes) -> None:
        if self._latest is not None:
            while len(self._backlog) >= self.budget:
                self._backlog.popleft()
                self.dropped += 1
            self._backlog.append(self._latest)
        self._latest = frame
        self._ready.set()

    async def next_frame(self) -> bytes:
        """The newest scan if one is unsent, else the oldest of the backlog (replayed)."""
        while True:
            if self._latest is not None:
                frame, self._latest = self._latest, None
                return frame
            if len(self._backlog):
                return with_flags(self._backlog.popleft(), FLAG_REPLAYED)
            self._ready.clear()
            await self._ready.wait()

    def unsent(self, frame: bytes) -> None:
        """A frame whose send failed (the link dropped): back in the backlog."""
        if len(self._backlog) < self.budget:
            self._backlog.appendleft(frame)
        else:
            self.dropped += 1


@dataclass
class RelayStats:
    scans: int = 0
    no_pose: int = 0  # turns the flight controller's pose did not cover: not sent


class ScanRelay:
    def __init__(
        self,
        source: ScanSource,
        poses: PoseHistory,
        outbox: ScanOutbox,
        mount: Mount | None = None,
        *,
        monotonic: Callable[[], float] = time.monotonic,
        wall: Callable[[], float] = time.time,
        reconnect: Backoff | None = None,
        source_name: str = "lidar",
    ) -> None:
        self.source = source
        self.source_name = source_name
        self.poses = poses
        self.outbox = outbox
        self.mount = mount or Mount()
        self.stats = RelayStats()
        self._monotonic = monotonic
        self._wall = wall
        self._reconnect = reconnect or Backoff(initial_s=0.5, max_s=5.0)
        self._seq = 0

    def source_stats(self) -> ScanSourceStats | None:
        """The source's counts (its parser's packets, points, drops by reason) for the
        hub's scan diagnostics; None before it has any."""
        counts = dict(list(self.source.stats.items())[:MAX_SOURCE_COUNTS])
        if not counts:
            return None
        return ScanSourceStats(source=self.source_name, counts=counts)

    async def run(self) -> None:
        retries = Retries(self._reconnect)
        while True:
            try:
                async for turn in self.source.turns():
                    retries.reset()
                    await self._relay(turn)
            except (OSError, ConnectionError, ValueError) as error:
                log.warning("LIDAR source failed: %s", error)
            await retries.wait()

    async def _relay(self, turn: Turn) -> None:
        frame = await self.stamp(turn)
        if frame is None:
            self.stats.no_pose += 1
            return
        self.outbox.put(encode_scan(frame))
        self.stats.scans += 1

    async def stamp(self, turn: Turn) -> ScanFrame | None:
        """The turn as a scan frame, with the poses at its start and end; None if the
        flight controller's pose does not cover it within POSE_WAIT_S."""
        clock = self.poses.clock
        if turn.fcu_start_s is not None:
            start, end = turn.fcu_start_s, turn.fcu_start_s + turn.duration_s
            # the board's stamp, on the agent's clock once it is known
            age = self._monotonic() - clock.to_monotonic(start) if clock.synced else 0.0
            utc = self._wall() - max(0.0, age)
        else:
            if not clock.synced:
                return None
            start = clock.to_fcu(turn.start)
            end = clock.to_fcu(turn.start + turn.duration_s)
            utc = self._wall() - (self._monotonic() - turn.start)
        deadline = self._monotonic() + POSE_WAIT_S
        while (latest := self.poses.latest_time()) is None or latest < end:
            if self._monotonic() >= deadline:
                return None
            await asyncio.sleep(POSE_POLL_S)
        pose_start, pose_end = self.poses.at(start), self.poses.at(end)
        if pose_start is None or pose_end is None:
            return None
        angle_min = turn.angle_min
        if turn.north_aligned:  # from north to the nose: the vehicle's yaw at that instant
            angle_min = math.remainder(angle_min + pose_start.yaw, 2.0 * math.pi)
        seq = self._seq
        self._seq += 1
        return ScanFrame(
            seq=seq,
            sensor_time_us=max(0, round(start * 1e6)),
            utc_time=utc,
            duration_s=min(1.0, max(1e-3, end - start)),
            angle_min=angle_min,
            angle_increment=turn.angle_increment,
            range_max_m=turn.range_max_m,
            pose_start=pose_start,
            pose_end=pose_end,
            ranges=turn.ranges,
            mount=self.mount,
        )


def parse_mount(text: str) -> Mount:
    """``forward,right,down,roll,pitch,yaw``: metres and degrees."""
    parts = [float(p) for p in text.split(",")]
    if len(parts) != 6 or not all(math.isfinite(p) for p in parts):
        raise ValueError("expected forward,right,down (m),roll,pitch,yaw (deg): six numbers")
    f, r, d, roll, pitch, yaw = parts
    return Mount(f, r, d, math.radians(roll), math.radians(pitch), math.radians(yaw))
