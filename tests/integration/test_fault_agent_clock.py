"""The agent's wall clock steps back and forward (a companion computer's time sync after
boot, a GPS time fix): the agent stamps each sample with that clock, so the stamps jump,
but the sequence numbers do not. Over a real WebSocket to a real hub.

Guaranteed: the live view keeps following the vehicle (newer by sequence number, not by
the stamp), every sample is stored once, and the flight opens and closes at the samples
where the vehicle armed and disarmed, whatever their stamps say.
"""

from __future__ import annotations

import time

import httpx
import pytest

from protocol.messages import Telemetry, VehicleState, encode
from tests.support.agents import scripted_agent
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher, connected, state_of

pytestmark = pytest.mark.integration

HOUR = 3600.0


def _sample(seq: int, at: float, armed: bool, alt: float) -> str:
    state = VehicleState(armed=armed, alt_rel=alt, mode="GUIDED")
    return encode(Telemetry(seq=seq, time=at, state=state))


def test_a_clock_that_steps_back_and_forward_keeps_the_live_view_and_the_flight_right(
    hub: str, admin_token: str, admin_api: httpx.Client
) -> None:
    token = admin_api.post("/api/v1/vehicles/v1/agent-tokens").json()["token"]
    now = time.time()
    # (first seq, clock offset, armed): on the ground, armed, the clock an hour back,
    # then two hours forward, then disarmed.
    phases = [(0, 0.0, False), (5, 0.0, True), (10, -HOUR, True), (15, HOUR, True)]
    phases.append((20, HOUR, False))
    with (
        scripted_agent(hub, "v1", token) as agent,
        FleetWatcher(hub, admin_token) as watcher,
    ):
        watcher.wait_until(connected("v1"), 10, "the agent")
        for first, offset, armed in phases:
            for seq in range(first, first + 5):
                agent.send(_sample(seq, now + offset + seq * 0.1, armed, float(seq)))
            last = first + 4
            watcher.wait_until(
                lambda v, last=last: state_of(v, "v1").get("alt_rel") == float(last),
                10,
                f"the live view to show sample {last} (clock offset {offset:+g} s)",
            )

    def stored() -> list[int]:
        page = admin_api.get(
            "/api/v1/vehicles/v1/telemetry", params={"start": 0, "end": now + 3 * HOUR}
        ).json()
        return sorted(sample["seq"] for sample in page["samples"])

    poll_until(lambda: stored() == list(range(25)), 20, "every sample stored once")
    flights = admin_api.get("/api/v1/flights", params={"vehicle_id": "v1"}).json()["flights"]
    assert len(flights) == 1, flights
    (flight,) = flights
    assert flight["start_time"] == pytest.approx(now + 0.5)  # sample 5, armed
    assert flight["end_time"] == pytest.approx(now + HOUR + 2.0)  # sample 20, disarmed
