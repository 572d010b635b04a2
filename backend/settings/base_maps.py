"""The online base maps: street map and aerial imagery, as XYZ URL templates."""

from __future__ import annotations

from typing import Self
from urllib.parse import urlsplit

from pydantic import BaseModel, Field, model_validator

OSM_TILE_URL = "https://tile.openstreetmap.org/{z}/{x}/{y}.png"
OSM_ATTRIBUTION = (
    '&copy; <a href="https://www.openstreetmap.org/copyright">OpenStreetMap</a> contributors'
)


class BaseMapSettings(BaseModel):
    """The street map and the imagery the dashboard may fetch online."""

    # The online base maps: XYZ URL templates ({z}/{x}/{y}, optionally {s} for a, b, c).
    # An empty URL turns one off; the CSP lets the browser reach exactly these hosts.
    basemap_url: str | None = Field(
        default=OSM_TILE_URL, description="the street map; empty turns it off"
    )
    basemap_attribution: str = Field(
        default="", description="shown with the street map; OpenStreetMap's for its tiles"
    )
    basemap_max_zoom: int = Field(default=19, ge=1, le=24)
    imagery_url: str | None = Field(default=None, description="aerial imagery; off when unset")
    imagery_attribution: str = ""
    imagery_max_zoom: int = Field(default=19, ge=1, le=24)

    @model_validator(mode="after")
    def _online_base_maps(self) -> Self:
        for name in ("basemap_url", "imagery_url"):
            url = getattr(self, name)
            if not url:
                setattr(self, name, None)  # empty: this base map is off
                continue
            problem = tile_url_problem(url)
            if problem:
                raise ValueError(f"GCS_{name.upper()} {problem}")
        if self.basemap_url == OSM_TILE_URL and not self.basemap_attribution:
            self.basemap_attribution = OSM_ATTRIBUTION  # its licence asks for it
        return self

    @property
    def online_tile_urls(self) -> list[str]:
        return [url for url in (self.basemap_url, self.imagery_url) if url]


def tile_url_problem(url: str) -> str:
    """Why an XYZ URL template cannot be used, or "" when it can."""
    parts = urlsplit(url)
    if parts.scheme not in ("https", "http") or not parts.netloc:
        return f"must be an http(s) URL, not {url!r}"
    missing = [key for key in ("{z}", "{x}", "{y}") if key not in url]
    if missing:
        return f"must hold {', '.join(missing)} (an XYZ template such as {OSM_TILE_URL})"
    return ""
