"""The hub serves offline tile sets at /tiles/<name>/{z}/{x}/{y}, behind the login."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest

from backend.settings import HubSettings
from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.support.api import access_token, api_client
from tests.support.hub_server import running_hub
from tests.support.map_tiles import png_tile, write_mbtiles, write_pmtiles

NORTH, SOUTH = png_tile((0, 128, 0), 16), png_tile((0, 0, 128), 16)
TILES = {(0, 0, 0): png_tile((200, 0, 0), 16), (1, 0, 0): NORTH, (1, 0, 1): SOUTH}


@pytest.fixture
def tile_hub(tmp_path: Path) -> Iterator[str]:
    tiles = tmp_path / "tiles"
    tiles.mkdir()
    write_mbtiles(tiles / "field.mbtiles", TILES, attribution="our survey")
    write_pmtiles(tiles / "region.pmtiles", TILES, attribution="© region")
    with running_hub(hub_settings(tmp_path)) as base_url:
        yield base_url


@pytest.fixture
def api(tile_hub: str) -> Iterator[httpx.Client]:
    with api_client(tile_hub, access_token(tile_hub, "admin", ADMIN_PASSWORD)) as client:
        yield client


def test_the_sets_are_listed_by_name_with_a_versioned_url(api: httpx.Client) -> None:
    listed = api.get("/api/v1/tiles")
    assert listed.status_code == 200, listed.text
    sets = {item["name"]: item for item in listed.json()}
    assert set(sets) == {"field", "region"}
    field = sets["field"]
    assert (field["kind"], field["media_type"], field["max_zoom"]) == ("mbtiles", "image/png", 1)
    assert field["attribution"] == "our survey"
    assert field["url"].startswith("/tiles/field/{z}/{x}/{y}?v=")


@pytest.mark.parametrize("name", ["field", "region"])
def test_a_tile_is_served_in_xyz_order_with_cache_headers(api: httpx.Client, name: str) -> None:
    url = next(s["url"] for s in api.get("/api/v1/tiles").json() if s["name"] == name)
    north = api.get(url.format(z=1, x=0, y=0))
    assert north.status_code == 200
    assert north.headers["content-type"] == "image/png"
    assert north.content == NORTH  # y=0 is the north: MBTiles' TMS row is flipped
    assert api.get(url.format(z=1, x=0, y=1)).content == SOUTH
    # Versioned: the browser keeps it; private: it was served to a logged-in user.
    assert north.headers["cache-control"] == "private, max-age=31536000, immutable"
    etag = north.headers["etag"]
    again = api.get(url.format(z=1, x=0, y=0), headers={"If-None-Match": etag})
    assert again.status_code == 304
    assert again.content == b""
    # Without the version (or with an old one) the tile may change: an hour.
    plain = api.get(f"/tiles/{name}/1/0/0")
    assert plain.headers["cache-control"] == "private, max-age=3600"


def test_a_missing_tile_or_set_is_404_and_a_bad_address_422(api: httpx.Client) -> None:
    missing = api.get("/tiles/field/1/1/1")
    assert missing.status_code == 404
    assert missing.headers["cache-control"] == "private, max-age=3600"
    unknown = api.get("/tiles/nowhere/0/0/0")
    assert unknown.status_code == 404
    assert "nowhere" in unknown.json()["detail"]
    outside = api.get("/tiles/field/1/2/0")
    assert outside.status_code == 422
    assert outside.json()["detail"][0]["loc"] == ["path", "x"]
    for bad in ("/tiles/field/31/0/0", "/tiles/..%2Fgcs/0/0/0", "/tiles/field/0/-1/0"):
        assert api.get(bad).status_code in (404, 422), bad


def test_tiles_need_a_login(tile_hub: str) -> None:
    anonymous = httpx.get(f"{tile_hub}/tiles/field/0/0/0")
    assert anonymous.status_code == 401
    assert anonymous.content != TILES[(0, 0, 0)]
    with httpx.Client(base_url=tile_hub) as browser:  # the dashboard's cookie works too
        login = browser.post(
            "/api/v1/auth/login", json={"username": "admin", "password": ADMIN_PASSWORD}
        )
        assert login.status_code in (200, 204), login.text
        assert browser.get("/tiles/field/0/0/0").content == TILES[(0, 0, 0)]


def test_the_csp_allows_exactly_the_configured_tile_hosts(tmp_path: Path) -> None:
    from backend.api.hardening import content_security_policy

    settings: HubSettings = hub_settings(
        tmp_path,
        basemap_url="https://{s}.tile.example.org/{z}/{x}/{y}.png",
        imagery_url="https://imagery.example.com/wmts/{z}/{y}/{x}.jpg",
    )
    csp = content_security_policy(*settings.online_tile_urls)
    img_src = next(part for part in csp.split("; ") if part.startswith("img-src"))
    assert img_src == (
        "img-src 'self' data: blob: https://a.tile.example.org https://b.tile.example.org "
        "https://c.tile.example.org https://imagery.example.com"
    )
    off = hub_settings(tmp_path, basemap_url="")
    assert off.basemap_url is None
    assert "img-src 'self' data: blob:;" in content_security_policy(*off.online_tile_urls)
    with pytest.raises(ValueError, match=r"must hold \{x\}"):
        hub_settings(tmp_path, imagery_url="https://imagery.example.com/{z}/{y}.png")
