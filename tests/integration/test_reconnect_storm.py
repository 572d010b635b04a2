"""A hub restarted under 200 agents: they all come back, spread out by their jittered
backoff, the hub serves the first while the rest connect, and every sample is stored
exactly once.

The agents are light but speak through the real agent code: each is a ``HubLink`` (the
agent's hub link: hello, reconnect with full-jitter backoff, replay of everything not
acknowledged) over its own ``Outbox`` (sequence numbers, acknowledgements, resends),
fed with numbered telemetry as ``TelemetryPublisher`` feeds it; only the flight
controller and its simulator are left out, 200 of which would not fit on two cores.
The hub is a real process on SQLite (the embedded default), killed with SIGKILL.
"""

from __future__ import annotations

import asyncio
import sqlite3
import time
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from common.retry import Backoff
from gcs.launcher import FleetPlan, LocalFleet, free_port
from protocol.messages import CommandOutcome, Telemetry, VehicleState, encode
from tests.support.hellos import agent_hello
from tests.support.hubs import TEST_HUB_ENV
from tests.support.waiting import poll_until_async
from vehicle_agents.hub.link import HubLink, HubTimeouts
from vehicle_agents.hub.outbox import Outbox

pytestmark = [pytest.mark.integration, pytest.mark.slow]

AGENTS = 200
RATE_HZ = 2.0  # per agent: 400 samples a second in all, enough to catch a lost one
# The agent's own reconnect policy (HubTimeouts' default): full jitter under a cap that
# doubles from 0.5 s to 10 s. An agent that starts knocking as the hub dies has failed
# at most about six times by the time a restarted hub answers, so it waits no more than
# 10 s more: every agent is back within this of the hub answering, with room for the
# hub's start and the machine's load.
BACK_WITHIN_S = 30.0
RECONNECT = Backoff(initial_s=0.5, max_s=10.0)


@dataclass
class LightAgent:
    """One vehicle's agent without a flight controller: numbered telemetry into the real
    outbox, and the real hub link."""

    vehicle_id: str
    token: str
    hub_ws: str
    outbox: Outbox = field(init=False)
    link: HubLink = field(init=False)
    produced: int = 0
    connects: list[float] = field(default_factory=list)

    def __post_init__(self) -> None:
        hello = agent_hello(self.vehicle_id, stream_id=f"{self.vehicle_id}-run")
        self.outbox = Outbox(hello.stream_id, limit=100_000)
        self.link = HubLink(
            f"{self.hub_ws}/api/v1/agent/ws",
            self.token,
            hello,
            self.outbox,
            self._command,
            timeouts=HubTimeouts(reconnect=RECONNECT),
        )

    async def _command(self, command: object) -> CommandOutcome:
        return CommandOutcome(status="accepted", message="ok")

    def publish(self) -> None:
        state = VehicleState(mode="LOITER", lat=47.0, lon=8.0, gps_fix=3)
        body = encode(Telemetry(seq=self.produced, time=time.time(), state=state))
        self.outbox.put("telemetry", self.produced, body)
        self.produced += 1

    async def produce(self, stop: asyncio.Event) -> None:
        period = 1.0 / RATE_HZ
        next_at = time.monotonic()
        while not stop.is_set():
            self.publish()
            next_at += period
            await asyncio.sleep(max(0.0, next_at - time.monotonic()))

    async def watch(self) -> None:
        """Notes each time the hub welcomes this agent."""
        while True:
            await self.link.connected.wait()
            self.connects.append(time.monotonic())
            await self.link.disconnected.wait()


def stored(database: Path) -> dict[str, list[int]]:
    with sqlite3.connect(database, timeout=30) as db:
        rows = db.execute(
            "SELECT vehicle_id, seq FROM telemetry ORDER BY vehicle_id, seq"
        ).fetchall()
    found: dict[str, list[int]] = {}
    for vehicle_id, seq in rows:
        found.setdefault(vehicle_id, []).append(int(seq))
    return found


def test_a_hub_restarted_under_200_agents_gets_them_all_back_with_every_sample_once(
    tmp_path: Path,
) -> None:
    plan = FleetPlan(vehicles=AGENTS, port=free_port(), data_dir=tmp_path)
    with LocalFleet(plan) as fleet:
        plan.data_dir.mkdir(mode=0o700, parents=True, exist_ok=True)
        fleet.log_dir.mkdir(mode=0o700, exist_ok=True)
        hub_env = {"GCS_VIZ_ENABLED": "false"}
        fleet.start_hub({**TEST_HUB_ENV, **hub_env})
        fleet.wait_until_ready(60)
        agents = [
            LightAgent(plan.vehicle_id(i), plan.agent_token(i), plan.hub_ws) for i in range(AGENTS)
        ]
        figures = asyncio.run(_storm(fleet, agents, hub_env))
        fleet.stop()
    print(
        f"\n{AGENTS} agents: all back {figures.all_back_s:.1f} s after the restarted hub "
        f"answered (first {figures.first_back_s:.1f} s, median {figures.median_back_s:.1f} s); "
        f"first backlog stored {figures.first_drained_s:.1f} s after it answered"
    )
    assert figures.all_back_s <= BACK_WITHIN_S
    # The hub served the first agents while the rest were still connecting.
    assert figures.first_drained_s < figures.all_back_s

    samples = stored(tmp_path / "gcs.sqlite3")
    for agent in agents:
        seqs = samples.get(agent.vehicle_id, [])
        assert seqs == list(range(agent.produced)), (
            f"{agent.vehicle_id}: {agent.produced} produced, {len(seqs)} stored, "
            f"{len(set(seqs))} distinct"
        )


@dataclass
class StormFigures:
    first_back_s: float
    median_back_s: float
    all_back_s: float
    first_drained_s: float


async def _storm(
    fleet: LocalFleet, agents: list[LightAgent], hub_env: dict[str, str]
) -> StormFigures:
    stop = asyncio.Event()
    async with asyncio.TaskGroup() as tasks:
        runners = [tasks.create_task(agent.link.run()) for agent in agents]
        watchers = [tasks.create_task(agent.watch()) for agent in agents]
        producers = [tasks.create_task(agent.produce(stop)) for agent in agents]
        await poll_until_async(
            lambda: all(agent.link.connected.is_set() for agent in agents),
            60,
            "every agent connected",
            every_s=0.2,
        )
        # Each agent's outbox fills while its hub is away.
        await asyncio.sleep(1.0)  # the test's input: a second of telemetry before the crash
        await asyncio.to_thread(fleet.kill, "hub")
        await poll_until_async(
            lambda: not any(agent.link.connected.is_set() for agent in agents),
            30,
            "every agent to see the hub gone",
        )
        await asyncio.sleep(2.0)  # the outage: the agents retry meanwhile
        await asyncio.to_thread(fleet.start_hub, hub_env)
        await asyncio.to_thread(fleet.wait_until_ready, 60)
        answered_at = time.monotonic()
        drained_at: list[float] = []

        def every_agent_back() -> bool:
            # The outage left each outbox a dozen samples or more; one down to the one or
            # two in flight has had its backlog stored.
            if not drained_at and any(
                agent.link.connected.is_set() and len(agent.outbox) <= 2 for agent in agents
            ):
                drained_at.append(time.monotonic())
            return all(agent.link.connected.is_set() for agent in agents)

        await poll_until_async(every_agent_back, 120, "every agent back", every_s=0.05)
        backs = sorted(max(0.0, agent.connects[-1] - answered_at) for agent in agents)
        await asyncio.sleep(1.0)  # the test's input: telemetry after the storm too
        stop.set()
        for producer in producers:
            await producer
        await poll_until_async(
            lambda: all(len(agent.outbox) == 0 for agent in agents),
            120,
            "every sample acknowledged as stored",
        )
        if not drained_at:
            drained_at.append(time.monotonic())
        for task in runners + watchers:
            task.cancel()
    return StormFigures(
        first_back_s=backs[0],
        median_back_s=backs[len(backs) // 2],
        all_back_s=backs[-1],
        first_drained_s=drained_at[0] - answered_at,
    )
