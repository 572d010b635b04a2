"""Agent tokens end to end: provisioned tokens in the operator's own form, the onboard
.tlog uploader's retries, and rotation through GCS_AGENT_TOKENS."""

from __future__ import annotations

import asyncio
from pathlib import Path
from typing import Any

import httpx

from backend.auth.accounts import Accounts
from backend.storage.database import make_engine
from common.retry import Backoff
from protocol.messages import AGENT_WS_PATH, CloseCode
from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.support.agents import close_code, scripted_agent, websocket
from tests.support.api import access_token, api_client
from tests.support.flights import OPERATOR_TOKEN, _heartbeat, _recorded_flight
from tests.support.hub_server import running_hub
from vehicle_agents.tlog.uploads import UPLOAD_BACKOFF, TlogUploader

LATER_TOKEN = "field-kit-alpha-rotated-9876543210"
FAST_RETRIES = Backoff(initial_s=0.05, max_s=0.2)


def _tlogs(api: httpx.Client, vehicle: str) -> list[dict[str, Any]]:
    response = api.get(f"/api/v1/vehicles/{vehicle}/tlogs")
    assert response.status_code == 200, response.text
    tlogs: list[dict[str, Any]] = response.json()
    return tlogs


def test_a_provisioned_token_without_prefix_uploads_a_tlog(tmp_path: Path) -> None:
    settings = hub_settings(tmp_path, agent_tokens=f"alpha={OPERATOR_TOKEN}")
    recorder = _recorded_flight(tmp_path / "onboard", "alpha")
    with running_hub(settings) as base, scripted_agent(base, "alpha", OPERATOR_TOKEN):
        response = httpx.post(
            f"{base}/api/v1/vehicles/alpha/tlogs",
            content=recorder.finished[0].read_bytes(),
            headers={
                "Authorization": f"Bearer {OPERATOR_TOKEN}",
                "Content-Type": "application/octet-stream",
                "X-Filename": recorder.finished[0].name,
            },
        )
        assert response.status_code == 201, response.text
        # The token still speaks for its own vehicle only.
        other = httpx.post(
            f"{base}/api/v1/vehicles/bravo/tlogs",
            content=b"x",
            headers={"Authorization": f"Bearer {OPERATOR_TOKEN}"},
        )
        assert other.status_code == 403


def test_a_refused_upload_is_reported_kept_and_retried(tmp_path: Path) -> None:
    """The hub refuses the uploader's token at first: the operator gets an event, the file
    stays queued, and once the token is provisioned the next retry hands it over."""
    settings = hub_settings(tmp_path, agent_tokens=f"alpha={OPERATOR_TOKEN}")
    recorder = _recorded_flight(tmp_path / "onboard", "alpha")
    flight = recorder.finished[0]
    events: list[tuple[str, int]] = []

    async def scenario(base: str) -> None:
        reported = asyncio.Event()

        def notify(text: str, severity: int) -> None:
            events.append((text, severity))
            reported.set()

        url = f"{base}/api/v1/vehicles/alpha/tlogs"
        uploader = TlogUploader(recorder, url, LATER_TOKEN, notify, FAST_RETRIES)
        async with asyncio.TaskGroup() as tasks:
            running = tasks.create_task(uploader.run())
            uploader.on_message(_heartbeat(armed=False))
            await asyncio.wait_for(reported.wait(), 20)
            ((text, severity),) = events
            assert "HTTP 401" in text
            assert "kept on board" in text
            assert severity == 4  # MAV_SEVERITY_WARNING
            assert list(recorder.finished) == [flight]
            assert flight.exists()
            assert not running.done()  # a refusal does not end the uploader

            reported.clear()
            engine = make_engine(settings.sqlalchemy_url)
            try:
                await asyncio.to_thread(
                    Accounts(engine).provision_agent_token, "alpha", LATER_TOKEN
                )
            finally:
                engine.dispose()
            await asyncio.wait_for(reported.wait(), 20)
            running.cancel()
        assert "uploaded after earlier failures" in events[-1][0]
        assert not recorder.finished
        assert (flight.parent / "uploaded" / flight.name).exists()

    with running_hub(settings) as base, scripted_agent(base, "alpha", OPERATOR_TOKEN):
        asyncio.run(scenario(base))
        with api_client(base, access_token(base, "admin", ADMIN_PASSWORD)) as api:
            (stored,) = _tlogs(api, "alpha")
            assert stored["size"] == flight.parent.joinpath("uploaded", flight.name).stat().st_size


def test_upload_backoff_doubles_from_5_s_to_10_min() -> None:
    assert [UPLOAD_BACKOFF.cap(n) for n in (1, 2, 3, 8, 20)] == [5, 10, 20, 600, 600]


def _refused_agent(base: str, token: str) -> tuple[int | None, str]:
    with websocket(base.replace("http://", "ws://") + AGENT_WS_PATH, _bearer(token)) as socket:
        return close_code(socket)


def _bearer(token: str) -> dict[str, str]:
    return {"Authorization": f"Bearer {token}"}


def test_a_token_rotated_in_the_configuration_is_revoked_at_start(tmp_path: Path) -> None:
    with running_hub(hub_settings(tmp_path, agent_tokens=f"alpha={OPERATOR_TOKEN}")) as base:
        with scripted_agent(base, "alpha", OPERATOR_TOKEN):
            pass
        with api_client(base, access_token(base, "admin", ADMIN_PASSWORD)) as api:
            enrolled = api.post("/api/v1/vehicles/bravo/agent-tokens").json()["token"]

    # The operator rotates alpha's token and restarts the hub.
    with running_hub(hub_settings(tmp_path, agent_tokens=f"alpha={LATER_TOKEN}")) as base:
        code, reason = _refused_agent(base, OPERATOR_TOKEN)
        assert code == CloseCode.UNAUTHORIZED, reason
        upload = httpx.post(
            f"{base}/api/v1/vehicles/alpha/tlogs", content=b"x", headers=_bearer(OPERATOR_TOKEN)
        )
        assert upload.status_code == 401
        with scripted_agent(base, "alpha", LATER_TOKEN), scripted_agent(base, "bravo", enrolled):
            pass  # the new token works, and a token enrolled through the API is untouched
        with api_client(base, access_token(base, "admin", ADMIN_PASSWORD)) as api:
            entries = api.get("/api/v1/audit", params={"action": "agent_token.revoke"}).json()
            tokens = api.get("/api/v1/agent-tokens").json()
    (entry,) = entries["entries"]
    assert (entry["actor"], entry["target"], entry["outcome"]) == ("provisioning", "alpha", "ok")
    assert "GCS_AGENT_TOKENS" in entry["detail"]["reason"]
    assert {(t["vehicle_id"], t["created_by"], t["revoked"]) for t in tokens} == {
        ("alpha", "provisioning", True),
        ("alpha", "provisioning", False),
        ("bravo", "admin", False),
    }

    # Removed from the configuration altogether: revoked as well.
    with running_hub(hub_settings(tmp_path)) as base:
        assert _refused_agent(base, LATER_TOKEN)[0] == CloseCode.UNAUTHORIZED
        with scripted_agent(base, "bravo", enrolled):
            pass
