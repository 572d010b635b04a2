"""Uploads with hostile names and contents: nothing lands outside the data directory, no
XML or image bomb is expanded, and each refusal is a 4xx that says why.

- KML (survey area import): a billion laughs and a quadratic blowup under expat's own
  amplification limit are both refused at the entity declaration, unexpanded;
- photos: a small JPEG whose header claims 20,000 x 20,000 px (400 MP) is refused before
  any decoding, and leaves no file behind; a photo id of dot names is refused;
- .tlog: a file name with ../ stays inside the vehicle's tlog folder;
- .plan (survey import): over the size limit, or nested past the parser, a 422.
"""

from __future__ import annotations

import io
import json
import time
from collections.abc import Callable
from pathlib import Path

import httpx
import pytest
from PIL import Image

from backend.survey.files.items import MAX_FILE_BYTES
from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.support.agents import scripted_agent
from tests.support.api import access_token, api_client
from tests.support.hub_server import running_hub
from tests.support.map_tiles import png_tile, write_mbtiles
from tests.support.tlogs import tlog_of

Enrol = Callable[[str], str]

KML_HEAD = '<?xml version="1.0"?>\n'
KML_BODY = (
    '<kml xmlns="http://www.opengis.net/kml/2.2"><Placemark><name>&e;</name><Polygon>'
    "<outerBoundaryIs><LinearRing><coordinates>149.16,-35.36 149.17,-35.36 149.17,-35.37"
    "</coordinates></LinearRing></outerBoundaryIs></Polygon></Placemark></kml>"
)
LAUGHS = "".join(
    f'<!ENTITY e{n} "{f"&e{n - 1};" * 10}">' if n else '<!ENTITY e0 "lol">' for n in range(10)
)
KML_BOMBS = {
    # 10^9 "lol"s: expat's own limit stops this one; our refusal comes first.
    "billion laughs": KML_HEAD + f'<!DOCTYPE kml [{LAUGHS}<!ENTITY e "&e9;">]>' + KML_BODY,
    # A 20 KB entity 200 times: 4 MB from a 24 KB file, a ratio expat lets through.
    "quadratic blowup": KML_HEAD
    + f'<!DOCTYPE kml [<!ENTITY e "{"x" * 20_000}">]>'
    + KML_BODY.replace("&e;", "&e;" * 200),
}


@pytest.mark.parametrize("kml", KML_BOMBS.values(), ids=KML_BOMBS.keys())
def test_a_kml_bomb_is_refused_unexpanded(admin_api: httpx.Client, kml: str) -> None:
    started = time.monotonic()
    response = admin_api.post("/api/v1/surveys/import", json={"format": "kml", "content": kml})
    assert response.status_code == 422, response.text[:500]
    assert "declares entities" in response.text
    assert time.monotonic() - started < 5


def test_a_kml_without_entities_still_reads(admin_api: httpx.Client) -> None:
    kml = KML_HEAD + KML_BODY.replace("&e;", "field")
    response = admin_api.post("/api/v1/surveys/import", json={"format": "kml", "content": kml})
    assert response.status_code == 200, response.text
    assert len(response.json()["area"]["coordinates"][0]) == 4


PLANS = {
    "over the limit": json.dumps({"fileType": "Plan", "pad": "x" * (MAX_FILE_BYTES + 1)}),
    "nested past the parser": "[" * 50_000 + "]" * 50_000,
    "no survey": json.dumps({"fileType": "Plan", "mission": {"items": []}}),
}


@pytest.mark.parametrize("plan", PLANS.values(), ids=PLANS.keys())
def test_a_hostile_plan_is_a_422_naming_the_content(hub: str, admin_token: str, plan: str) -> None:
    with api_client(hub, admin_token) as api:
        response = api.post("/api/v1/surveys/import", json={"format": "plan", "content": plan})
    # over the 1 MB body limit the transport refuses it first
    assert response.status_code in (413, 422), response.text[:500]
    assert "content" in response.text or "limit" in response.text


def _claimed_size_jpeg(width: int, height: int) -> bytes:
    """A 16 x 16 JPEG whose frame header (SOF0) claims ``width`` x ``height``."""
    out = io.BytesIO()
    Image.new("RGB", (16, 16), (90, 120, 60)).save(out, "JPEG")
    data = bytearray(out.getvalue())
    sof = data.index(b"\xff\xc0")
    data[sof + 5 : sof + 9] = height.to_bytes(2, "big") + width.to_bytes(2, "big")
    return bytes(data)


def _meta(photo_id: str, size: int, width: int, height: int) -> str:
    return json.dumps(
        {
            "photo_id": photo_id,
            "index": 1,
            "size_bytes": size,
            "pose": {
                "lat": -35.36,
                "lon": 149.16,
                "alt_msl": 600,
                "alt_rel": 30,
                "roll": 0,
                "pitch": 0,
                "yaw": 0,
                "time": time.time(),
            },
            "camera": {
                "sensor_width_mm": 13.2,
                "sensor_height_mm": 8.8,
                "image_width_px": width,
                "image_height_px": height,
                "focal_length_mm": 8.8,
            },
        }
    )


def test_a_photo_claiming_400_megapixels_is_refused_before_decoding(tmp_path: Path) -> None:
    with running_hub(hub_settings(tmp_path)) as hub:
        admin = access_token(hub, "admin", ADMIN_PASSWORD)
        with api_client(hub, admin) as api:
            token = api.post("/api/v1/vehicles/cam/agent-tokens").json()["token"]
        bomb = _claimed_size_jpeg(20_000, 20_000)
        assert len(bomb) < 2_000
        with scripted_agent(hub, "cam", token), api_client(hub, token) as agent:
            response = agent.put(
                "/api/v1/vehicles/cam/photos/bomb",
                content=bomb,
                headers={"X-Photo-Meta": _meta("bomb", len(bomb), 20_000, 20_000)},
            )
        assert response.status_code == 422, response.text
        assert response.json()["code"] == "corrupt_image"
        assert "pixels" in response.json()["detail"]
        leftovers = [p for p in (tmp_path / "photos").rglob("*") if p.is_file()]
        assert not leftovers, leftovers


@pytest.mark.parametrize("photo_id", ["..", "."])
def test_a_photo_id_of_dot_names_is_refused(hub: str, enrol: Enrol, photo_id: str) -> None:
    token = enrol("cam")
    with scripted_agent(hub, "cam", token), api_client(hub, token) as agent:
        # sent as it is: httpx would fold the dots into the path
        url = httpx.URL(f"{hub}/api/v1/vehicles/cam/photos/x").copy_with(
            raw_path=f"/api/v1/vehicles/cam/photos/{photo_id.replace('.', '%2E')}".encode()
        )
        response = agent.put(url, content=b"\xff\xd8", headers={"X-Photo-Meta": "{}"})
    assert 400 <= response.status_code < 500, response.text


def test_a_tlog_name_with_dot_dot_slashes_stays_in_its_folder(
    tmp_path: Path, hub: str, enrol: Enrol, admin_api: httpx.Client
) -> None:
    token = enrol("tl")
    with scripted_agent(hub, "tl", token), api_client(hub, token) as agent:
        response = agent.post(
            "/api/v1/vehicles/tl/tlogs",
            content=tlog_of(4_000),
            headers={"X-Filename": "../../../../etc/cron.d/evil.tlog"},
        )
    assert response.status_code == 201, response.text
    name = response.json()["filename"]
    assert "/" not in name
    assert "\\" not in name
    stored = list((tmp_path / "tlogs").rglob("*"))
    files = [p for p in stored if p.is_file()]
    assert len(files) == 1
    assert files[0].parent == tmp_path / "tlogs" / "tl"
    downloaded = admin_api.get(f"/api/v1/tlogs/{response.json()['id']}")
    assert downloaded.status_code == 200
    assert "/" not in downloaded.headers["content-disposition"].split("filename=")[1]


def test_corrupt_and_hostile_tile_files_are_skipped_not_served(tmp_path: Path) -> None:
    """Tile sets are files an operator drops in the tiles folder: a truncated, garbage or
    renamed file, or a symlink out of the folder, is left out of the list, and asking
    for it is a 404, never a 500."""
    tiles = tmp_path / "tiles"
    tiles.mkdir()
    write_mbtiles(tiles / "good.mbtiles", {(0, 0, 0): png_tile((0, 128, 0), 16)})
    (tiles / "garbage.mbtiles").write_bytes(b"\x00" * 4096)
    (tiles / "garbage.pmtiles").write_bytes(b"PMTiles\x03" + b"\xff" * 200)
    (tiles / "empty.pmtiles").write_bytes(b"")
    (tiles / "text.mbtiles").write_text("SQLite format 3\x00 but not really")
    (tiles / "outside.mbtiles").symlink_to(tmp_path / "elsewhere.mbtiles")
    with running_hub(hub_settings(tmp_path)) as hub:
        admin = access_token(hub, "admin", ADMIN_PASSWORD)
        with api_client(hub, admin) as api:
            listed = api.get("/api/v1/tiles")
            assert listed.status_code == 200, listed.text
            assert [s["name"] for s in listed.json()] == ["good"]
            for name in ("garbage", "empty", "text", "outside"):
                response = api.get(f"/tiles/{name}/0/0/0")
                assert response.status_code == 404, (name, response.text)
            assert api.get("/tiles/good/0/0/0").status_code == 200
