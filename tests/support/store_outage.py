"""What the store-outage fault tests share: an agent streaming telemetry through the
outage, the safety commands that must go on meanwhile, and the check that every sample
the hub accepted was stored once the store is back."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from contextlib import contextmanager

import httpx

from tests.support.agents import ScriptedAgent, telemetry_frame
from tests.support.databases import answering
from tests.support.waiting import poll_until

VEHICLE = "v1"


class Stream:
    """How many samples the streaming agent has sent (numbered from 0)."""

    def __init__(self) -> None:
        self.sent = 0


@contextmanager
def streaming(agent: ScriptedAgent, rate_hz: float) -> Iterator[Stream]:
    """The agent sends numbered telemetry at ``rate_hz`` until the block ends."""
    stream = Stream()
    stop = threading.Event()

    def send() -> None:
        while not stop.is_set():
            agent.send(telemetry_frame(stream.sent))
            stream.sent += 1
            stop.wait(1 / rate_hz)  # the agent's sampling rate

    sender = threading.Thread(target=send, daemon=True)
    sender.start()
    try:
        yield stream
    finally:
        stop.set()
        sender.join(10)


def stored(api: httpx.Client) -> list[int]:
    """The sequence numbers stored for the vehicle; none while the store is away."""
    page = api.get(f"/api/v1/vehicles/{VEHICLE}/telemetry", params={"start": 0, "limit": 10000})
    if page.status_code == 503:  # the database is away: nothing can be read
        return []
    page.raise_for_status()
    return sorted(sample["seq"] for sample in page.json()["samples"])


def degraded(api: httpx.Client, what: str) -> dict[str, object]:
    """/health once it reports the store away (the live fleet still answering)."""
    health: dict[str, object] = poll_until(
        lambda: (h := api.get("/api/v1/health").json())["status"] == "degraded" and h,
        30,
        f"/health to report {what}",
    )
    assert health["database_available"] is False
    assert api.get("/api/v1/vehicles").status_code == 200
    return health


def safety_commands_go_through(api: httpx.Client, agent: ScriptedAgent) -> None:
    """Land, RTL and hold reach the agent and are answered while the store is away."""
    for name in ("land", "rtl", "hold"):
        with answering(agent) as received:
            answer = api.post(f"/api/v1/vehicles/{VEHICLE}/commands", json={"name": name})
            assert answer.status_code == 200, answer.text
            assert answer.json()["outcome"]["status"] == "accepted"
        assert [command["name"] for command in received] == [name]


def everything_stored(api: httpx.Client, sent: int) -> None:
    """Every sample sent stored exactly once, and the commands' log rows too."""
    poll_until(
        lambda: api.get("/api/v1/health").json()["rows_spooled"] == 0 and len(stored(api)) >= sent,
        60,
        f"all {sent} samples and the spooled rows stored",
    )
    assert stored(api) == list(range(sent)), "a sample is missing or stored twice"
    commands = api.get("/api/v1/commands", params={"vehicle_id": VEHICLE}).json()
    assert sorted(c["name"] for c in commands["commands"]) == ["hold", "land", "rtl"]
