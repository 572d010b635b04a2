"""Replayed and forged sequence numbers from an agent: each frame is stored once, frames
after a forged jump are still stored, and the acknowledgement stays at the last frame
stored without a hole (a forged jump cannot make the agent forget unsent frames)."""

from __future__ import annotations

import json
from collections.abc import Callable

import httpx

from protocol.messages import MAX_SEQ
from tests.support.agents import scripted_agent, telemetry_frame, wait_stored

Enrol = Callable[[str], str]


def test_replayed_decreasing_and_huge_sequence_numbers(
    hub: str, enrol: Enrol, admin_api: httpx.Client
) -> None:
    sent = (0, 1, 2, MAX_SEQ, 1, 0, 2, 3, 4)
    with scripted_agent(hub, "sq", enrol("sq"), delivery=True) as agent:
        for seq in sent:
            agent.send(telemetry_frame(seq))
        wait_stored(admin_api, "sq", 6)
        acked, resend = -1, None
        while acked < 4 or resend is None:
            reply = json.loads(agent.recv(timeout=10))
            if reply["type"] == "ack" and reply["telemetry_seq"] is not None:
                acked = reply["telemetry_seq"]
                assert acked < MAX_SEQ, reply  # never past the hole the forgery opened
            elif reply["type"] == "resend":
                resend = reply
    page = admin_api.get("/api/v1/vehicles/sq/telemetry", params={"start": 0, "limit": 100}).json()
    assert sorted(sample["seq"] for sample in page["samples"]) == [0, 1, 2, 3, 4, MAX_SEQ]
    assert acked == 4
    assert resend is not None
    assert (resend["first_seq"], resend["last_seq"]) == (3, MAX_SEQ - 1)
