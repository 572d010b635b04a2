"""A second GCS behind the agent's MAVLink forward asks for its own, lower, stream rates
again and again (as MAVProxy does every ~15 s: REQUEST_DATA_STREAM for every group, here
with a SET_MESSAGE_INTERVAL too), for five minutes of simulated time. The flight
controller (the simulator, which keeps ArduPilot's one set of rates per link) is sent the
highest rate each stream needs, once: the agent's position rate holds within 5 % of its
10 Hz all along, the agent logs no rate warning and never asks again, and the GCS has an
answer to every SET_MESSAGE_INTERVAL it sent (issue #35).

The simulator times its streams in sim time (as SITL with SIM_SPEEDUP), so here one
clock, SPEEDUP times the wall's, drives everything that times the rates: the simulator's
physics and streams, the agent's rate watch and the second GCS's cadence; the agent's
parts run in-process (FcuLink, StreamRequester, MavlinkForwarder) to read it. The clock
holds through a stall of the process (``max_step_s``), as SITL's lockstep does, so a busy
machine slows the flight down instead of losing its messages. Five simulated minutes
take 25 s. The rates are measured from GLOBAL_POSITION_INT's own time_boot_ms.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from dataclasses import dataclass, field
from typing import Any

import pytest
from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from gcs.launcher import free_port
from simulator import ListenAddress, SimClock, SimulatorConfig
from tests.support.simulators import serving
from vehicle_agents.fcu.link import FcuLink
from vehicle_agents.fcu.messages import MavMessage
from vehicle_agents.fcu.stream_watch import RateWatchSettings
from vehicle_agents.fcu.streams import StreamRequester, StreamTimeouts
from vehicle_agents.forwarding.forwarder import MavlinkForwarder

pytestmark = [pytest.mark.integration, pytest.mark.slow]

SPEEDUP = 12.0
# Of the wall time between two readings of the clock (the simulator reads it every tick,
# 10 ms at most), no more than this counts: a longer stall is lost, not flown.
MAX_STEP_S = 0.05
ACK_WAIT_S = 0.4  # wall: the agent waits for its acknowledgements on the wall clock
DURATION_S = 300.0  # simulated
SETTLE_S = 20.0  # the agent's own requests, before the rates are held to account
WINDOW_S = 20.0
MAVPROXY_IDS = (250, 230)
MAVPROXY_EVERY_S = 15.0  # simulated: how often MAVProxy asks again
POSITION_HZ = 10.0  # the agent's default for GLOBAL_POSITION_INT
GCS_POSITION_HZ = 4.0  # the second GCS's own, lower


@dataclass
class SecondGcs:
    """MAVProxy's habit, played by pymavlink through the forward's udpin endpoint."""

    port: int
    clock: SimClock
    requests: int = 0
    acks: list[Any] = field(default_factory=list)

    def run(self) -> None:
        connection = mavutil.mavlink_connection(
            f"udpout:127.0.0.1:{self.port}",
            source_system=MAVPROXY_IDS[0],
            source_component=MAVPROXY_IDS[1],
        )
        mav = connection.mav
        try:
            next_at = 0.0
            while self.clock.now() < DURATION_S + 1.0:
                if self.clock.now() >= next_at:
                    mav.heartbeat_send(
                        mavlink2.MAV_TYPE_GCS, mavlink2.MAV_AUTOPILOT_INVALID, 0, 0, 0
                    )
                    mav.request_data_stream_send(
                        1, 1, mavlink2.MAV_DATA_STREAM_ALL, int(GCS_POSITION_HZ), 1
                    )
                    mav.command_long_send(
                        1,
                        1,
                        mavlink2.MAV_CMD_SET_MESSAGE_INTERVAL,
                        0,
                        mavlink2.MAVLINK_MSG_ID_GLOBAL_POSITION_INT,
                        1e6 / GCS_POSITION_HZ,
                        0,
                        0,
                        0,
                        0,
                        0,
                    )
                    self.requests += 1
                    next_at += MAVPROXY_EVERY_S
                # What the forward sends it, read as it comes (the wait is the read's).
                message = connection.recv_match(type="COMMAND_ACK", blocking=True, timeout=0.05)
                if message is not None and message.target_system == MAVPROXY_IDS[0]:
                    self.acks.append(message)
        finally:
            connection.close()


def test_a_second_gcs_asking_lower_rates_for_five_minutes_changes_nothing(
    caplog: pytest.LogCaptureFixture,
) -> None:
    caplog.set_level(logging.INFO, logger="vehicle_agents")
    config = SimulatorConfig(listen=ListenAddress("tcp", "127.0.0.1", 0), speedup=SPEEDUP)
    clock = SimClock(SPEEDUP, max_step_s=MAX_STEP_S)
    with serving(config, clock=clock) as (_, address):
        positions: list[int] = []  # time_boot_ms of each GLOBAL_POSITION_INT at the agent

        def count(message: MavMessage) -> None:
            if message.get_type() == "GLOBAL_POSITION_INT":
                positions.append(int(message.time_boot_ms))

        async def main() -> tuple[StreamRequester, MavlinkForwarder, SecondGcs]:
            link = FcuLink(f"tcp:127.0.0.1:{address.port}")
            # The rate watch in simulated time, judged every simulated second.
            streams = StreamRequester(
                link,
                {},
                timeouts=StreamTimeouts(ack_s=ACK_WAIT_S, watch_every_s=1.0 / SPEEDUP),
                watch=RateWatchSettings(),
                clock=clock.now,
            )
            port = free_port()
            forward = MavlinkForwarder(link, [f"udpin:127.0.0.1:{port}"], streams.merger)
            link.listeners.append(count)
            gcs = SecondGcs(port, clock)
            tasks = [asyncio.create_task(part.run()) for part in (link, streams, forward)]
            try:
                await asyncio.wait_for(link.wait_identified(), 10)
                await asyncio.to_thread(gcs.run)
            finally:
                for task in tasks:
                    task.cancel()
                for task in tasks:
                    with contextlib.suppress(asyncio.CancelledError):
                        await task
            return streams, forward, gcs

        streams, forward, gcs = asyncio.run(main())

    assert gcs.requests >= DURATION_S / MAVPROXY_EVERY_S
    rates = []
    start = SETTLE_S
    while start + WINDOW_S <= DURATION_S:
        within = [t for t in positions if start * 1000 <= t < (start + WINDOW_S) * 1000]
        rates.append(len(within) / WINDOW_S)
        start += WINDOW_S
    print(
        f"\nGLOBAL_POSITION_INT at the agent per {WINDOW_S:g} s window (Hz): "
        f"{', '.join(f'{r:.2f}' for r in rates)}; {gcs.requests} requests from the second "
        f"GCS, {forward.merger.absorbed} absorbed"
    )
    assert len(rates) == int((DURATION_S - SETTLE_S) // WINDOW_S)
    assert all(abs(rate - POSITION_HZ) <= 0.05 * POSITION_HZ for rate in rates), rates
    warnings = [r for r in caplog.records if r.levelno >= logging.WARNING]
    assert not warnings, [r.getMessage() for r in warnings]
    assert streams.watch.rerequests == 0
    # Every SET_MESSAGE_INTERVAL had its answer, ACCEPTED (the GCS gets at least 4 Hz).
    assert len(gcs.acks) == gcs.requests
    assert {ack.result for ack in gcs.acks} == {mavlink2.MAV_RESULT_ACCEPTED}
    assert forward.merger.absorbed > 0
