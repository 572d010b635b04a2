"""The hub's survey planner (backend/survey/plan_workers.py): a plan past its time limit is a
422 naming the setting and its worker process is killed; a client that goes away stops its
plan (its worker killed too); past the plans allowed at once, a 429."""

from __future__ import annotations

import asyncio
import os
import time
from pathlib import Path

import pytest

from backend.errors import InvalidRequest, RateLimited
from backend.observability import metrics
from backend.survey.plan_workers import ClientGone, SurveyPlanner
from backend.survey.planning.schemas import SurveyRequest
from backend.survey.planning.survey import Fleet
from common.geodesy import GeoPoint, LocalFrame
from tests.conftest import hub_settings
from tests.support.waiting import poll_until, poll_until_async

FRAME = LocalFrame(47.0, 8.0, 0.0)


def _slow_plan() -> tuple[SurveyRequest, list[Fleet]]:
    """Within every limit, but seconds of work: three drones over a 200 m square at 5 m."""
    ring = [list(reversed(FRAME.to_geo(x, y))) for x, y in [(0, 0), (200, 0), (200, 200), (0, 200)]]
    request = SurveyRequest.model_validate(
        {
            "area": {"type": "Polygon", "coordinates": [[*ring, ring[0]]]},
            "camera": "sony_a6000_16mm",
            "altitude_m": 5,
            "vehicle_ids": ["a", "b", "c"],
        }
    )
    lat, lon = FRAME.to_geo(-20, -20)
    here = GeoPoint(lat, lon)
    return request, [Fleet(vid, here, here) for vid in request.vehicle_ids]


async def _workers_done() -> None:
    await poll_until_async(
        lambda: metrics.SURVEY_PLANS_RUNNING._value.get() == 0, 5, "the workers done", every_s=0.01
    )


def test_a_plan_past_its_time_limit_is_refused_and_its_worker_killed(tmp_path: Path) -> None:
    planner = SurveyPlanner(hub_settings(tmp_path, survey_plan_timeout_s=0.3))

    async def run() -> tuple[float, list[int]]:
        plan = asyncio.ensure_future(planner.plan(*_slow_plan()))
        busy = await poll_until_async(planner.pool.pids, 20, "the plan's worker", every_s=0.01)
        started = time.monotonic()
        with pytest.raises(InvalidRequest, match=r"longer than 0.3 s.*survey_plan_timeout_s"):
            await plan
        await _workers_done()
        try:
            return time.monotonic() - started, busy
        finally:
            planner.close()

    took, busy = asyncio.run(run())
    assert took < 2.5
    for pid in busy:
        poll_until(lambda pid=pid: not _alive(pid), 5, f"worker {pid} killed")


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


def test_a_client_gone_stops_its_plan(tmp_path: Path) -> None:
    planner = SurveyPlanner(hub_settings(tmp_path))
    stopped = metrics.SURVEY_PLANS_STOPPED.labels(reason="disconnect")

    async def run() -> None:
        before = stopped._value.get()
        with pytest.raises(ClientGone):
            await planner.plan(*_slow_plan(), gone=lambda: asyncio.sleep(0.3))
        await _workers_done()
        assert stopped._value.get() == before + 1

    try:
        asyncio.run(run())
    finally:
        planner.close()


def test_plans_past_the_pending_bound_are_a_429(tmp_path: Path) -> None:
    planner = SurveyPlanner(hub_settings(tmp_path, survey_plan_max_pending=1))

    async def run() -> None:
        first = asyncio.ensure_future(planner.plan(*_slow_plan(), gone=lambda: asyncio.sleep(0.5)))
        await asyncio.sleep(0.1)
        with pytest.raises(RateLimited, match="survey_plan_max_pending"):
            await planner.plan(*_slow_plan())
        with pytest.raises(ClientGone):
            await first
        await _workers_done()

    try:
        asyncio.run(run())
    finally:
        planner.close()
