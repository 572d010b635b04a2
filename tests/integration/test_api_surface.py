"""The versioned API surface and its documentation."""

from __future__ import annotations

import httpx


def test_rest_routes_are_versioned_and_documented(hub: str) -> None:
    with httpx.Client(base_url=hub) as api:
        schema = api.get("/openapi.json").json()
        assert api.get("/docs").status_code == 200
    paths = set(schema["paths"])
    assert {
        "/api/v1/vehicles",
        "/api/v1/vehicles/{vehicle_id}",
        "/api/v1/vehicles/{vehicle_id}/commands",
        "/api/v1/vehicles/{vehicle_id}/telemetry",
        "/api/v1/health",
        "/api/v1/config",
    } <= paths
    assert all(path.startswith("/api/v1/") for path in paths)


def test_health_and_config(hub: str, admin_api: httpx.Client) -> None:
    health = httpx.get(f"{hub}/api/v1/health").json()  # public: a load balancer's probe
    config = admin_api.get("/api/v1/config").json()
    assert health["status"] == "ok"
    assert health["vehicles"] == 0
    # OpenStreetMap's standard tiles by default, with the attribution its licence asks for
    assert config["basemap_url"] == "https://tile.openstreetmap.org/{z}/{x}/{y}.png"
    assert "OpenStreetMap" in config["basemap_attribution"]
    assert config["imagery_url"] is None  # imagery is off until a URL is set
    assert config["protocol"] == 1
