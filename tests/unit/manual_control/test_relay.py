"""The manual relay: newest wins, at most 100 Hz per vehicle, what it drops is counted."""

from __future__ import annotations

import asyncio

from backend.fleet.commands import AgentChannel
from backend.fleet.registry import FleetRegistry
from backend.manual_control.relay import ManualRelay
from protocol.messages import ManualAxes, ManualFrame, Message
from tests.support.hellos import agent_hello


def frame(seq: int) -> ManualFrame:
    return ManualFrame(seq=seq, axes=ManualAxes(x=seq, y=0))


def test_a_burst_collapses_to_its_newest_frame_and_a_flood_to_100_hz() -> None:
    async def scenario() -> tuple[list[int], list[int], int, int]:
        sent: list[Message] = []
        arrived = asyncio.Event()

        async def send(message: Message) -> None:
            sent.append(message)
            arrived.set()

        registry = FleetRegistry()
        registry.connect(agent_hello("v"), AgentChannel(send))
        dropped = 0

        def count() -> None:
            nonlocal dropped
            dropped += 1

        relay = ManualRelay(registry, max_rate_hz=100.0, on_collapse=count)
        runner = asyncio.create_task(relay.run())
        # A stalled client's socket flushes eight frames at once (no await between them,
        # as the feed reads frames already buffered): only the newest is flown.
        for seq in range(1, 9):
            relay.put("v", frame(seq))
        await asyncio.wait_for(arrived.wait(), 1)
        burst = [f.seq for f in sent if isinstance(f, ManualFrame)]
        burst_dropped = dropped
        # A flood at 1 kHz for 0.2 s: at most one frame per 10 ms goes on, the newest.
        sent.clear()
        started = asyncio.get_running_loop().time()
        seq = 100
        while asyncio.get_running_loop().time() - started < 0.2:
            seq += 1
            relay.put("v", frame(seq))
            await asyncio.sleep(0.001)  # pacing the test's own flood
        await asyncio.sleep(0.05)  # the last waiting frame's turn (10 ms at most)
        runner.cancel()
        flood = [f.seq for f in sent if isinstance(f, ManualFrame)]
        return burst, flood, burst_dropped, seq

    burst, flood, burst_dropped, last = asyncio.run(scenario())
    assert burst == [8]
    assert burst_dropped == 7
    put = last - 100
    assert len(flood) <= 22, flood  # 100 Hz for 0.2 s at most, give or take the loop
    assert len(flood) < put  # the flood was thinned
    assert flood == sorted(flood)  # never an older frame after a newer one
    assert flood[-1] == last  # the newest of the flood is the last flown
