"""Scans from agents: checked, counted, stored, mapped, and offered to subscribers.

What a scan goes through, in order (bad input is refused or cleaned, and counted in the
vehicle's diagnostics; the agent's connection survives either way):
1. `protocol.scans.decode_scan`: size, magic, version, beam count against the header,
   finite header fields, positions in range. NaN, infinite or negative ranges cannot be
   sent (ranges are uint16); ranges beyond the sensor's stated maximum are cleaned to "no
   return" and counted, so no point is ever placed at infinity.
2. Time: more than `FUTURE_LIMIT_S` ahead of the hub's clock, or older than
   `PAST_LIMIT_S` (the agent keeps ten minutes), is refused.
3. Rate: live scans beyond ``scan_max_rate_hz`` per vehicle are refused, counted on the
   scans' own times, not on their arrival: a hub that stalls (its store applying
   backpressure while an outage's backlog replays) reads a second's worth of a 10 Hz
   sensor's scans in a burst, and those are not too many. An agent that spaces fake
   times to pass reaches the future limit within seconds. Replayed scans (after an
   outage) are paced by storage instead: the store's queue is bounded and waits, so
   backpressure reaches the agent.
4. The vehicle: a scan arrives on an agent's own connection, whose token was checked
   against its vehicle id at the hello; a frame has no vehicle id of its own, so one
   agent cannot send scans for another.

Then it is queued for the store (every scan), placed in the point map, and, if live,
published for subscribers, newest wins per vehicle. Obstacles are extracted from the map
now and then (`refresh_obstacles`) and tracked, so that each keeps an id and its
appearing and going can be published as events.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections import Counter, deque
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from backend.realtime.bus import Bus, Topic
from backend.scans.obstacles import ObstacleChanges, ObstacleTracker
from backend.scans.pointmap import PointMap
from backend.scans.points import WorldPoints, world_points
from backend.scans.repository import ScanRepository, StoredScan
from common.geodesy import LocalFrame
from protocol.scans import NO_RETURN, ScanFrame, ScanFrameError, client_scan_frame, decode_scan

log = logging.getLogger(__name__)

FUTURE_LIMIT_S = 60.0
PAST_LIMIT_S = 86400.0
STORE_BATCH = 200
STORE_INTERVAL_S = 0.2


class ScanRejected(ValueError):
    """A scan refused; ``reason`` is the diagnostics counter it adds to."""

    def __init__(self, reason: str, message: str) -> None:
        super().__init__(message)
        self.reason = reason
        self.message = message


@dataclass
class ScanDiagnostics:
    received: int = 0
    live: int = 0
    replayed: int = 0
    stored: int = 0
    cleaned_ranges: int = 0
    rejected: Counter[str] = field(default_factory=Counter)
    # the agent's own word on its LIDAR source (protocol.messages.ScanSourceStats)
    source: str | None = None
    source_counts: dict[str, int] = field(default_factory=dict)


@dataclass(frozen=True)
class LatestScan:
    vehicle_id: str
    frame: ScanFrame
    points: WorldPoints


@dataclass(frozen=True)
class ScanDelivery:
    """What a subscriber gets: the scan frame with its vehicle's id in front."""

    vehicle_id: str
    data: bytes


class ScanService:
    def __init__(
        self,
        repository: ScanRepository,
        bus: Bus,
        *,
        site: LocalFrame | None = None,
        voxel_m: float = 0.1,
        max_voxels: int = 500_000,
        max_rate_hz: float = 20.0,
        queue_limit: int = 2000,
        clock: Callable[[], float] = time.time,
    ) -> None:
        self.repository = repository
        self.bus = bus
        self.site = site
        self.point_map = PointMap(voxel_m, max_voxels)
        self.max_rate_hz = max_rate_hz
        self.diagnostics: dict[str, ScanDiagnostics] = {}
        self.latest: dict[str, LatestScan] = {}
        self._recent: dict[str, deque[float]] = {}
        self._queue: asyncio.Queue[StoredScan] = asyncio.Queue(queue_limit)
        self._clock = clock
        self.obstacles = ObstacleTracker()
        self.mapped_by: str | None = None  # the vehicle whose scan last went into the map
        self._map_changes = 0
        self._obstacles_at = -1  # the map change the obstacles were last found at
        self._obstacle_lock = asyncio.Lock()

    @property
    def map_version(self) -> int:
        """Counts the changes to the point map: equal counts, the same map."""
        return self._map_changes

    def diagnostics_of(self, vehicle_id: str) -> ScanDiagnostics:
        return self.diagnostics.setdefault(vehicle_id, ScanDiagnostics())

    def source_reported(self, vehicle_id: str, source: str, counts: dict[str, int]) -> None:
        """The agent's latest word on its scan source: kept for the diagnostics only."""
        diagnostics = self.diagnostics_of(vehicle_id)
        diagnostics.source = source
        diagnostics.source_counts = counts

    async def ingest(self, vehicle_id: str, stream_id: str, data: bytes) -> ScanFrame:
        """Check, store, map and publish one scan frame; ScanRejected if refused."""
        counts = self.diagnostics_of(vehicle_id)
        counts.received += 1
        try:
            frame = self._check(vehicle_id, data, counts)
        except ScanRejected as refusal:
            counts.rejected[refusal.reason] += 1
            raise
        site = self.site_for(frame)
        points = world_points(frame, site)
        self.point_map.add(points.enu, frame.utc_time)
        self.mapped_by = vehicle_id
        self._map_changes += 1
        stored = StoredScan(vehicle_id, stream_id, frame.seq, frame.utc_time, frame.beams, data)
        await self._queue.put(stored)  # reliable: waits when the store is behind
        if frame.replayed:
            counts.replayed += 1
        else:
            counts.live += 1
            self.latest[vehicle_id] = LatestScan(vehicle_id, frame, points)
            delivery = ScanDelivery(vehicle_id, client_scan_frame(vehicle_id, data))
            await self.bus.publish(Topic.SCANS, vehicle_id, delivery)
        return frame

    async def refresh_obstacles(self) -> ObstacleChanges:
        """The obstacles in the point map now, matched to the last ones found (in a
        thread: clustering a full map takes a while); no work if the map is unchanged."""
        async with self._obstacle_lock:
            if self._obstacles_at == self._map_changes:
                return ObstacleChanges(self.obstacles.current, [], [])
            self._obstacles_at = self._map_changes
            found = await asyncio.to_thread(self.point_map.obstacles)
            return self.obstacles.update(found)

    def site_for(self, frame: ScanFrame) -> LocalFrame:
        """The site's frame; without a configured origin, the first scan's position
        (live, or the first one read back from the store after a restart)."""
        if self.site is None:
            pose = frame.pose_start
            self.site = LocalFrame(pose.lat, pose.lon, pose.alt_msl)
            log.info("site origin set from a scan: %s", self.site.origin)
        return self.site

    def _check(self, vehicle_id: str, data: bytes, counts: ScanDiagnostics) -> ScanFrame:
        try:
            frame = decode_scan(data)
        except ScanFrameError as error:
            raise ScanRejected("bad_frame", str(error)) from None
        now = self._clock()
        if frame.utc_time > now + FUTURE_LIMIT_S:
            raise ScanRejected(
                "time_future", f"utc_time: {frame.utc_time - now:.0f} s in the future"
            )
        if frame.utc_time < now - PAST_LIMIT_S:
            raise ScanRejected("time_past", f"utc_time: {now - frame.utc_time:.0f} s in the past")
        if not frame.replayed:
            recent = self._recent.setdefault(vehicle_id, deque())
            at = frame.utc_time
            while recent and (recent[0] <= at - 1.0 or recent[-1] > at):
                # out of the window, or after this scan: the agent's clock stepped back
                if recent[0] <= at - 1.0:
                    recent.popleft()
                else:
                    recent.pop()
            if len(recent) >= self.max_rate_hz:
                raise ScanRejected(
                    "rate", f"more than {self.max_rate_hz:g} scans/s from {vehicle_id}"
                )
            recent.append(at)
        ranges = np.frombuffer(frame.ranges, dtype=np.uint16)  # a view: writes go through
        beyond = ranges > round(frame.range_max_m / frame.range_scale)
        if beyond.any():
            counts.cleaned_ranges += int(beyond.sum())
            ranges[beyond] = NO_RETURN
        return frame

    async def run(self) -> None:
        """Store queued scans in batches until cancelled."""
        while True:
            batch = [await self._queue.get()]
            deadline = asyncio.get_running_loop().time() + STORE_INTERVAL_S
            while len(batch) < STORE_BATCH:
                try:
                    remaining = deadline - asyncio.get_running_loop().time()
                    batch.append(await asyncio.wait_for(self._queue.get(), max(0.0, remaining)))
                except TimeoutError:
                    break
            try:
                await asyncio.to_thread(self.repository.insert, batch)
            except Exception as error:
                # The store is down: these scans are lost (counted); the live path goes on.
                log.warning("could not store %d scans: %s", len(batch), error)
                for scan in batch:
                    self.diagnostics_of(scan.vehicle_id).rejected["store_failed"] += 1
                continue
            for scan in batch:
                self.diagnostics_of(scan.vehicle_id).stored += 1
