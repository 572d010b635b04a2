"""The dashboards' live feed carries the vehicles' events as they happen (issue 16)."""

from __future__ import annotations

import time
from collections.abc import Callable

import pytest

from protocol.messages import Event, encode
from tests.support.agents import scripted_agent
from tests.support.watcher import FleetWatcher

pytestmark = pytest.mark.integration


def _has_event(watcher: FleetWatcher, kind: str, text: str) -> Callable[[object], bool]:
    return lambda _: any(e["kind"] == kind and text in e["text"] for e in watcher.events)


def test_agent_and_hub_events_reach_the_live_feed(
    hub: str, admin_token: str, enrol: Callable[[str], str]
) -> None:
    token = enrol("ev_1")
    with FleetWatcher(hub, admin_token) as watcher:
        with scripted_agent(hub, "ev_1", token) as agent:
            watcher.wait_until(_has_event(watcher, "link_up", "agent connected"), 10, "link up")
            for seq in range(3):  # an autopilot repeats its pre-arm failure
                prearm = Event(
                    seq=seq,
                    time=time.time(),
                    kind="statustext",
                    severity=2,
                    text="PreArm: Need Position Estimate",
                )
                agent.send(encode(prearm))
            watcher.wait_until(_has_event(watcher, "statustext", "PreArm"), 10, "the pre-arm text")
        watcher.wait_until(_has_event(watcher, "link_down", "disconnected"), 10, "link down")
    prearm_events = [e for e in watcher.events if "PreArm" in e["text"]]
    assert sum(e["repeat"] for e in prearm_events) == 3
    assert all(e["vehicle_id"] == "ev_1" and e["severity"] == 2 for e in prearm_events)
    assert watcher.dropped_events == 0
