"""Once the hub has stored an onboard .tlog, the agent prunes its uploaded files by age and
size budget, keeping every file the hub does not have and the flight being written."""

from __future__ import annotations

import asyncio
import os
import time
from pathlib import Path

import pytest

from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.support.agents import scripted_agent
from tests.support.api import access_token, api_client
from tests.support.flights import OPERATOR_TOKEN, _heartbeat, _recorded_flight
from tests.support.hub_server import running_hub
from tests.support.waiting import poll_until_async
from vehicle_agents.tlog.pruning import DAY_S, UPLOADED_DIR, TlogRetention
from vehicle_agents.tlog.uploads import TlogUploader

pytestmark = pytest.mark.integration


def _aged(path: Path, size: int, age_days: float) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(b"\xfd" * size)
    mtime = time.time() - age_days * DAY_S
    os.utime(path, (mtime, mtime))
    return path


def test_after_an_upload_the_agent_prunes_uploaded_tlogs_only(tmp_path: Path) -> None:
    onboard = tmp_path / "onboard"
    recorder = _recorded_flight(onboard, "alpha")
    flight = recorder.finished[0]
    recorder.record(_heartbeat(armed=True), time.time())  # the next flight, being written
    recording = recorder.recording
    assert recording is not None
    expired = _aged(onboard / UPLOADED_DIR / "alpha_expired.tlog", 1000, age_days=8)
    earlier = _aged(onboard / UPLOADED_DIR / "alpha_earlier.tlog", 1000, age_days=1)
    # Never uploaded (the hub refused it, say) and long past the age limit: it stays.
    stuck = _aged(onboard / "alpha_stuck.tlog", 1000, age_days=30)
    # Room for what must stay, and 500 bytes: `earlier` goes too, for the budget.
    budget = sum(path.stat().st_size for path in (flight, stuck, recording)) + 500
    retention = TlogRetention(keep_days=7, keep_bytes=budget)

    async def scenario(base: str) -> None:
        url = f"{base}/api/v1/vehicles/alpha/tlogs"
        uploader = TlogUploader(recorder, url, OPERATOR_TOKEN, retention=retention)
        async with asyncio.TaskGroup() as tasks:
            running = tasks.create_task(uploader.run())
            uploader.on_message(_heartbeat(armed=True))
            uploaded = onboard / UPLOADED_DIR / flight.name
            await poll_until_async(
                lambda: uploaded.exists() and not earlier.exists(), 20, "the pruning"
            )
            running.cancel()

    settings = hub_settings(tmp_path, agent_tokens=f"alpha={OPERATOR_TOKEN}")
    try:
        with running_hub(settings) as base, scripted_agent(base, "alpha", OPERATOR_TOKEN):
            asyncio.run(scenario(base))
            with api_client(base, access_token(base, "admin", ADMIN_PASSWORD)) as api:
                (stored,) = api.get("/api/v1/vehicles/alpha/tlogs").json()
            assert stored["size"] == (onboard / UPLOADED_DIR / flight.name).stat().st_size
        assert recording.exists()
    finally:
        recorder.close()
    assert not expired.exists()
    assert not earlier.exists()
    assert (onboard / UPLOADED_DIR / flight.name).exists()  # within both limits
    assert stuck.exists()
