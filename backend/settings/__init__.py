"""The hub's settings (GCS_* variables), a module per area: `server` (socket, store,
folders, HTTP limits), `accounts`, `rails` (safety rails' defaults), `live` (agents,
commands, feeds), `scans` (point map, 3D view), `surveys`, `bus` (several hubs),
`retention`, `base_maps`; `production` refuses what a production hub must not start
with; `hub_settings` joins them into HubSettings. Import them from here."""

from __future__ import annotations

from backend.settings.base_maps import OSM_ATTRIBUTION, OSM_TILE_URL, tile_url_problem
from backend.settings.bus import redacted_url
from backend.settings.hub_settings import HubSettings
from backend.settings.production import SECRET_FILE_VARIABLES, WEAK_SECRETS
from backend.settings.server import REPO_ROOT

__all__ = [
    "OSM_ATTRIBUTION",
    "OSM_TILE_URL",
    "REPO_ROOT",
    "SECRET_FILE_VARIABLES",
    "WEAK_SECRETS",
    "HubSettings",
    "redacted_url",
    "tile_url_problem",
]
