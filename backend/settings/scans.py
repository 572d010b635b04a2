"""The LIDAR's point map and the 3D view."""

from __future__ import annotations

from pydantic import BaseModel, Field

from common.geodesy import LocalFrame


class ScanSettings(BaseModel):
    """The site's frame, the point map, its obstacles and the 3D view."""

    viz_enabled: bool = Field(default=True, description="serve the 3D view (viser) at /viz/")
    viz_origin: str | None = Field(
        default=None,
        pattern=r"^\s*-?[0-9.]+\s*,\s*-?[0-9.]+\s*(,\s*-?[0-9.]+\s*)?$",
        description="'lat,lon[,alt_msl]' of the 3D view's local east-north-up origin; "
        "the first home position the fleet reports when unset",
    )
    viz_update_interval_s: float = Field(
        default=0.1, ge=0.02, le=5.0, description="the 3D scene's batched update period"
    )
    viz_trail_s: float = Field(default=60.0, ge=0, le=3600, description="3D trail length")

    site_origin: str | None = Field(
        default=None,
        pattern=r"^-?\d+(\.\d+)?,-?\d+(\.\d+)?,-?\d+(\.\d+)?$",
        description="LAT,LON,ALT_MSL of the site's east-north-up frame (scans' world points, "
        "the point map); unset: the first scan's position",
    )
    scan_voxel_m: float = Field(
        default=0.1, ge=0.01, le=5.0, description="the point map's voxel size"
    )
    scan_map_max_voxels: int = Field(
        default=500_000,
        ge=1000,
        description="the point map's bound (about 100 bytes each): the least recently seen "
        "voxels go first",
    )
    scan_max_rate_hz: float = Field(
        default=20.0, gt=0, le=100, description="live scans per second per vehicle, at most"
    )
    scan_queue_limit: int = Field(default=2000, ge=10, description="scans waiting to be stored")

    scan_obstacle_interval_s: float = Field(
        default=5.0,
        gt=0,
        description="how often obstacles are extracted from the point map; one found or "
        "gone is an event (kind 'obstacle')",
    )

    def site_frame(self) -> LocalFrame | None:
        """The site's east-north-up frame, if an origin is configured."""
        if self.site_origin is None:
            return None
        lat, lon, alt = (float(part) for part in self.site_origin.split(","))
        return LocalFrame(lat, lon, alt)
