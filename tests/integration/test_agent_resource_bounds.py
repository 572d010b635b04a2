"""An agent token cannot make the hub store or send without bound.

Uploads: a .tlog must be timestamped MAVLink frames (a file of zeros is refused and not
kept), one file is bounded, and so is all that a vehicle stores. Messages: a hello with
a 60 KB list of modes (which every dashboard would receive with each of the vehicle's
updates) is refused at the door.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterator
from pathlib import Path

import httpx
import pytest

from protocol.messages import AGENT_WS_PATH, MAX_FRAME_BYTES, CloseCode
from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.support.agents import close_code, scripted_agent, websocket
from tests.support.api import access_token, api_client
from tests.support.hellos import agent_hello
from tests.support.hub_server import running_hub
from tests.support.tlogs import tlog_of

pytestmark = pytest.mark.integration

VEHICLE = "quota_1"
PER_FILE = 64 * 1024
PER_VEHICLE = 100 * 1024


@pytest.fixture
def small_quota_hub(tmp_path: Path) -> Iterator[str]:
    settings = hub_settings(
        tmp_path, max_tlog_bytes=PER_FILE, max_tlog_bytes_per_vehicle=PER_VEHICLE
    )
    with running_hub(settings) as base:
        yield base


def _upload(base: str, token: str, body: bytes) -> httpx.Response:
    return httpx.post(
        f"{base}/api/v1/vehicles/{VEHICLE}/tlogs",
        content=body,
        headers={"Authorization": f"Bearer {token}", "X-Filename": "flight.tlog"},
        timeout=30,
    )


def test_uploads_must_be_tlogs_and_fit_the_quota(
    small_quota_hub: str, enrol: Callable[[str], str], tmp_path: Path
) -> None:
    base = small_quota_hub
    token = enrol(VEHICLE)
    stored = tmp_path / "tlogs" / VEHICLE
    with scripted_agent(base, VEHICLE, token):  # the vehicle is known to the hub
        pass

    zeros = _upload(base, token, bytes(40_000))
    assert zeros.status_code == 422, zeros.text
    assert "not a MAVLink .tlog" in zeros.text
    noise = _upload(base, token, b"\xfd" * 40_000)  # a magic byte is not a frame
    assert noise.status_code == 422, noise.text

    first = _upload(base, token, tlog_of(45_000))
    assert first.status_code == 201, first.text
    too_big = _upload(base, token, tlog_of(PER_FILE + 1000))
    assert too_big.status_code == 413, too_big.text
    second = _upload(base, token, tlog_of(45_000))
    assert second.status_code == 201, second.text
    over_quota = _upload(base, token, tlog_of(45_000))
    assert over_quota.status_code == 413, over_quota.text
    assert "quota" in over_quota.json()["detail"]

    with api_client(base, access_token(base, "admin", ADMIN_PASSWORD)) as api:
        listed = api.get(f"/api/v1/vehicles/{VEHICLE}/tlogs").json()
    assert [entry["size"] for entry in listed] == [len(tlog_of(45_000))] * 2
    assert len(list(stored.iterdir())) == 2, "nothing refused is kept on disk"


def test_a_hello_with_60_kb_of_modes_is_refused(hub: str, enrol: Callable[[str], str]) -> None:
    token = enrol(VEHICLE)
    hello = agent_hello(VEHICLE, stream_id="s1").model_dump() | {"modes": ["M" * 30] * 1800}
    assert 55_000 < len(json.dumps(hello)) < MAX_FRAME_BYTES
    url = hub.replace("http://", "ws://") + AGENT_WS_PATH
    with websocket(url, {"Authorization": f"Bearer {token}"}) as socket:
        socket.send(json.dumps(hello))
        code, reason = close_code(socket)
    assert code == CloseCode.BAD_HELLO, (code, reason)
    assert "modes" in reason
    with api_client(hub, access_token(hub, "admin", ADMIN_PASSWORD)) as api:
        assert api.get(f"/api/v1/vehicles/{VEHICLE}").status_code == 404
