"""The leader's scans as its followers get them: the scan service's newest scan of the
leader, on the formation's plane, thinned, and without the ground."""

from __future__ import annotations

from backend.fleet.registry import FleetRegistry
from backend.formation.relay import ScanPoints, ScanSource
from backend.scans.points import in_frame
from backend.scans.service import ScanService
from common.geodesy import LocalFrame
from protocol.messages import MAX_SCAN_POINTS

# A formation's followers get the leader's scans thinned to one point per cell this wide.
SCAN_CELL_M = 0.2
# ...and without the returns this close above the leader's home: the ground, reached by a
# scan tilted as the leader accelerates, is not an obstacle.
SCAN_GROUND_M = 0.3


def leader_scans(scans: ScanService, registry: FleetRegistry) -> ScanSource:
    """The relay's scan source over ``scans``."""

    def leader_scan(vehicle_id: str, frame: LocalFrame, after_seq: int | None) -> ScanPoints | None:
        """A formation leader's newest live scan on the formation's plane, if it is not
        the one numbered ``after_seq``."""
        latest = scans.latest.get(vehicle_id)
        site = scans.site
        if latest is None or site is None or latest.frame.seq == after_seq:
            return None
        state = registry.get(vehicle_id).state
        home = state.home_alt_msl if state is not None else None
        ground = None if home is None else home + SCAN_GROUND_M
        north, east = in_frame(
            latest.points, site, frame, SCAN_CELL_M, MAX_SCAN_POINTS, above_msl=ground
        )
        return ScanPoints(latest.frame.utc_time, latest.frame.seq, north, east)

    return leader_scan
