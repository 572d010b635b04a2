"""The flight controller link under stress: rate requests and their fallback, garbage on
the wire, a link cut or silenced and restored, a better GPS coming and going, and rates
another GCS lowers restored.

The simulator runs in-process; the agent is a real process talking to it over TCP, either
directly or through ``FcuTap``, a `CuttableProxy` that reads what the agent asks for and can
corrupt, silence or cut what the flight controller sends back.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import httpx
import pytest
from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from gcs.launcher import free_port
from simulator import SimulatorServer
from simulator.config import MessageIntervalSupport
from simulator.mavlink.message_context import SecondGps
from tests.support.api import api_client
from tests.support.fcu import (
    SET_MESSAGE_INTERVAL,
    SYSID,
    FcuTap,
    sim_config,
    state_of,
)
from tests.support.processes import agent_process
from tests.support.simulators import serving
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher
from vehicle_agents.fcu.link import FcuLink
from vehicle_agents.fcu.stream_plan import DEFAULT_RATES_HZ
from vehicle_agents.fcu.stream_watch import RateWatchSettings
from vehicle_agents.fcu.streams import StreamRequester, StreamTimeouts
from vehicle_agents.forwarding.forwarder import MavlinkForwarder

pytestmark = pytest.mark.integration


# -- rate requests, agent link against the simulator in one event loop ----------------


async def request_and_read_back(port: int, rates: dict[str, float]) -> tuple[str, dict[str, int]]:
    """One round of stream requests; then each message's interval as the FCU reports it."""
    link = FcuLink(f"tcp:127.0.0.1:{port}")
    requester = StreamRequester(link, rates, StreamTimeouts(ack_s=0.5, attempts=2))
    async with asyncio.TaskGroup() as tasks:
        running = tasks.create_task(link.run())
        await asyncio.wait_for(link.wait_identified(), 10)
        method = await requester.request()
        intervals = {}
        # Requests are handled in order, so these answers reflect the ones before.
        for name in ("GLOBAL_POSITION_INT", "ATTITUDE", "VFR_HUD", "GPS_RAW_INT", "HOME_POSITION"):
            msg_id = getattr(mavlink2, f"MAVLINK_MSG_ID_{name}")
            link.send_command_long(mavlink2.MAV_CMD_GET_MESSAGE_INTERVAL, 0, [msg_id])
            reply = await link.wait_for(
                lambda m, msg_id=msg_id: (
                    m.get_type() == "MESSAGE_INTERVAL" and m.message_id == msg_id
                ),
                5,
            )
            assert reply is not None, f"no MESSAGE_INTERVAL for {name}"
            intervals[name] = int(reply.interval_us)
        running.cancel()
    return method, intervals


def test_rates_are_set_per_message() -> None:
    with serving(sim_config()) as (_server, address):
        method, intervals = asyncio.run(
            request_and_read_back(address.port, {"ATTITUDE": 4, "VFR_HUD": 0, "HOME_POSITION": 1})
        )
    assert method == "message_interval"
    assert intervals == {
        "GLOBAL_POSITION_INT": 100_000,  # the agent's default
        "ATTITUDE": 250_000,  # overridden
        "VFR_HUD": -1,  # stopped
        "GPS_RAW_INT": 500_000,
        "HOME_POSITION": 1_000_000,
    }


@pytest.mark.parametrize("support", ["unsupported", "silent"])
def test_old_flight_controllers_get_data_streams(support: MessageIntervalSupport) -> None:
    with serving(sim_config(message_interval=support)) as (_server, address):
        method, intervals = asyncio.run(
            request_and_read_back(address.port, {"ATTITUDE": 4, "VFR_HUD": 0, "HOME_POSITION": 1})
        )
    assert method == "data_stream"
    assert intervals == {
        "GLOBAL_POSITION_INT": 100_000,  # POSITION group at 10 Hz
        "ATTITUDE": 250_000,  # EXTRA1 at the fastest of its messages
        "VFR_HUD": -1,  # EXTRA2 stopped
        "GPS_RAW_INT": 500_000,  # EXTENDED_STATUS at 2 Hz
        "HOME_POSITION": 2_000_000,  # in no group: the simulator's default stays
    }


# -- a proxy that sees and spoils the link ----------------------------------------------


# -- what the agent reports --------------------------------------------------------------


def fcu_link_events(api: httpx.Client, vehicle: str, kind: str) -> list[dict[str, Any]]:
    """The agent's events about its flight controller link, newest first (the hub logs
    its own link_up/link_down for the agent's connection)."""
    params = {"vehicle_id": vehicle, "kind": kind}
    events: list[dict[str, Any]] = api.get("/api/v1/events", params=params).json()["events"]
    return [event for event in events if event["text"].startswith("flight controller")]


def wait_for_events(
    api: httpx.Client, vehicle: str, kind: str, count: int, timeout_s: float
) -> list[dict[str, Any]]:
    """The agent has sent them; the hub's batching writer stores them: poll the store."""

    def enough() -> list[dict[str, Any]] | None:
        events = fcu_link_events(api, vehicle, kind)
        return events if len(events) >= count else None

    # the writer flushes every 0.25 s
    events = poll_until(enough, timeout_s, f"{count} {kind} events", every_s=0.1)
    assert events is not None  # poll_until returns a true value
    return events


def test_garbage_on_the_fcu_link_is_skipped_and_counted(
    hub: str, admin_token: str, enrol: Callable[[str], str], tmp_path: Path
) -> None:
    vehicle = "noisy"
    state = state_of(vehicle)
    with (
        serving(sim_config()) as (_server, address),
        FcuTap(address.port) as tap,
        agent_process(hub, enrol(vehicle), vehicle, tap.port, log_dir=tmp_path) as agent,
        FleetWatcher(hub, admin_token) as watcher,
    ):
        watcher.wait_until(lambda v: state(v).get("lat") is not None, 30, "a clean link first")
        # Each injection costs the few frames after it; a few seconds apart, they can
        # never swallow three heartbeats in a row (which would rightly be a lost link).
        tap.corrupt_every = 100
        watcher.wait_until(
            lambda v: state(v).get("fcu_receive_errors", 0) > 0, 15, "receive errors counted"
        )
        first = state(watcher.vehicles)["fcu_receive_errors"]
        # the link survives: fresh telemetry keeps coming, with ever more errors skipped
        watcher.wait_until(
            lambda v: (
                state(v).get("fcu_receive_errors", 0) >= first + 15
                and state(v).get("fcu_connected") is True
            ),
            30,
            "telemetry still flowing through the noise",
        )
        assert 0 < tap.injections <= state(watcher.vehicles)["fcu_receive_errors"]
        with api_client(hub, admin_token) as api:
            [summary] = [s for s in api.get("/api/v1/vehicles").json() if s["id"] == vehicle]
            assert summary["state"]["fcu_receive_errors"] > first
            assert summary["state"]["lat"] == pytest.approx(-35.363262, abs=1e-4)
            assert summary["state"]["position_source"] == "GPS_RAW_INT"
            assert fcu_link_events(api, vehicle, "link_down") == []
        assert agent.poll() is None


def test_a_lost_fcu_link_is_reported_retried_and_reshaped(
    hub: str, admin_token: str, enrol: Callable[[str], str], tmp_path: Path
) -> None:
    vehicle = "tethered"
    state = state_of(vehicle)
    requests_per_round = len(DEFAULT_RATES_HZ)
    with (
        serving(sim_config()) as (_server, address),
        FcuTap(address.port) as tap,
        agent_process(hub, enrol(vehicle), vehicle, tap.port, log_dir=tmp_path) as agent,
        FleetWatcher(hub, admin_token) as watcher,
        api_client(hub, admin_token) as api,
    ):
        watcher.wait_until(lambda v: state(v).get("fcu_connected") is True, 30, "the FCU link")
        tap.wait_for_interval_requests(requests_per_round, 15)

        # The cable is pulled: the socket closes, reconnecting is refused for a while.
        tap.cut()
        watcher.wait_until(lambda v: state(v).get("fcu_connected") is False, 15, "link lost")
        [down] = wait_for_events(api, vehicle, "link_down", 1, 15)
        assert "flight controller link lost" in down["text"]
        tap.start()  # plugged back in
        watcher.wait_until(lambda v: state(v).get("fcu_connected") is True, 20, "link back")
        [up] = wait_for_events(api, vehicle, "link_up", 1, 15)
        assert up["text"] == "flight controller link restored"
        assert up["time"] >= down["time"]
        # every rate is asked for again on the new connection
        tap.wait_for_interval_requests(2 * requests_per_round, 15)

        # The radio goes out of range: the connection stays, nothing comes through.
        tap.silence()
        watcher.wait_until(lambda v: state(v).get("fcu_connected") is False, 15, "silence")
        downs = wait_for_events(api, vehicle, "link_down", 2, 15)
        assert "flight controller link lost" in downs[0]["text"]
        assert "3 s" in downs[0]["text"]  # the heartbeat (or any valid MAVLink) timeout
        tap.speak()
        watcher.wait_until(lambda v: state(v).get("fcu_connected") is True, 20, "heard again")
        wait_for_events(api, vehicle, "link_up", 2, 15)
        tap.wait_for_interval_requests(3 * requests_per_round, 15)
        assert agent.poll() is None


def test_position_source_follows_the_better_receiver(
    hub: str, admin_token: str, enrol: Callable[[str], str], tmp_path: Path
) -> None:
    vehicle = "rtk"
    state = state_of(vehicle)
    config = sim_config(gps2_fix=mavlink2.GPS_FIX_TYPE_RTK_FIXED)
    with (
        serving(config) as (server, address),
        agent_process(hub, enrol(vehicle), vehicle, address.port, log_dir=tmp_path),
        FleetWatcher(hub, admin_token) as watcher,
    ):

        def source(name: str, fix: int, satellites: int) -> Callable[[Any], bool]:
            return lambda v: (
                (
                    state(v).get("position_source"),
                    state(v).get("gps_fix"),
                    state(v).get("satellites"),
                )
                == (name, fix, satellites)
            )

        watcher.wait_until(source("GPS2_RAW", 6, 18), 30, "the RTK receiver chosen")
        unplug(server)
        watcher.wait_until(source("GPS_RAW_INT", 3, 10), 15, "the primary GPS once RTK is stale")
        plug_in(server, SecondGps(mavlink2.GPS_FIX_TYPE_RTK_FLOAT, 14))
        watcher.wait_until(source("GPS2_RAW", 5, 14), 15, "the RTK receiver back")


def unplug(server: SimulatorServer) -> None:
    # One attribute, read by the simulator's loop thread at its next tick.
    server.telemetry.gps2 = None


def plug_in(server: SimulatorServer, gps2: SecondGps) -> None:
    server.telemetry.gps2 = gps2


# -- a second GCS lowers the rates: the agent notices and asks again -------------------


def lower_rates_as_mavproxy(gcs: Any) -> None:
    """MAVProxy's default: every stream at 4 Hz, one REQUEST_DATA_STREAM for all."""
    gcs.mav.request_data_stream_send(SYSID, 1, mavlink2.MAV_DATA_STREAM_ALL, 4, 1)


def lower_rates_per_message(gcs: Any) -> None:
    """QGroundControl's or MAVSDK's way: one message, by SET_MESSAGE_INTERVAL."""
    gcs.mav.command_long_send(
        SYSID,
        1,
        SET_MESSAGE_INTERVAL,
        0,
        mavlink2.MAVLINK_MSG_ID_GLOBAL_POSITION_INT,
        250_000,
        0,
        0,
        0,
        0,
        0,
    )


@pytest.mark.parametrize(
    "lower", [lower_rates_as_mavproxy, lower_rates_per_message], ids=["data_stream", "interval"]
)
def test_rates_another_gcs_lowers_are_restored(
    lower: Callable[[Any], None], caplog: pytest.LogCaptureFixture
) -> None:
    gcs_port = free_port()
    arrivals: list[float] = []

    def rate_hz(until: float) -> float:
        return sum(1 for t in arrivals if until - 1.0 < t <= until) / 1.0

    async def run(port: int) -> None:
        link = FcuLink(f"tcp:127.0.0.1:{port}")
        requester = StreamRequester(
            link,
            {},
            StreamTimeouts(ack_s=0.5, attempts=2, watch_every_s=0.2),
            RateWatchSettings(window_s=1.0),
        )
        link.listeners.append(
            lambda m: (
                arrivals.append(time.monotonic()) if m.get_type() == "GLOBAL_POSITION_INT" else None
            )
        )
        forwarder = MavlinkForwarder(link, [f"udpin:127.0.0.1:{gcs_port}"])
        gcs = mavutil.mavlink_connection(
            f"udpout:127.0.0.1:{gcs_port}", source_system=250, source_component=230
        )

        def next_position() -> Any:  # the test's tick: no sleeps, the vehicle's clock
            return link.wait_for(lambda m: m.get_type() == "GLOBAL_POSITION_INT", 1.0)

        try:
            async with asyncio.TaskGroup() as tasks:
                running = [
                    tasks.create_task(link.run()),
                    tasks.create_task(requester.run()),
                    tasks.create_task(forwarder.run()),
                ]
                await asyncio.wait_for(link.wait_identified(), 10)
                asked_at = time.monotonic()
                while requester.rounds < 1 or time.monotonic() < asked_at + 1.2:
                    await next_position()  # the rates set, and a window at them
                    assert time.monotonic() < asked_at + 10, "no round of requests"
                assert rate_hz(time.monotonic()) >= 8
                lowered_at = time.monotonic()
                gcs.mav.heartbeat_send(
                    mavlink2.MAV_TYPE_GCS, mavlink2.MAV_AUTOPILOT_INVALID, 0, 0, 0
                )
                lower(gcs)
                now = lowered_at
                while rate_hz(now) < 8 or "GLOBAL_POSITION_INT back at" not in caplog.text:
                    assert now < lowered_at + 15, f"rate stayed at {rate_hz(now)} Hz"
                    await next_position()
                    now = time.monotonic()
                # it was lowered in between: some second after the other GCS asked was slow
                ends = [lowered_at + 1.0 + 0.1 * i for i in range(int((now - lowered_at) * 10))]
                assert min(rate_hz(t) for t in ends) <= 5.5
                for task in running:
                    task.cancel()
        finally:
            gcs.close()

    caplog.set_level(logging.INFO, "vehicle_agents.fcu.stream_watch")
    with serving(sim_config()) as (_server, address):
        asyncio.run(run(address.port))
    assert "GLOBAL_POSITION_INT arrives at" in caplog.text
    assert "GLOBAL_POSITION_INT back at" in caplog.text
