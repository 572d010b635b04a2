"""The agent's flight-controller side against the simulator in this process: a link
and a command executor over real TCP, and a tap that can cut or spoil the link."""

from __future__ import annotations

import asyncio
import contextlib
import threading
from collections.abc import Awaitable, Callable, Iterator
from typing import Any, TypeVar

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from simulator import ListenAddress, SimulatorConfig, SimulatorServer
from simulator.config import Autopilot
from tests.support.simulators import serving
from tests.support.tcp_proxy import CuttableProxy, Filter
from vehicle_agents.control.executor import CommandExecutor
from vehicle_agents.fcu.commands import CommandTimeouts
from vehicle_agents.fcu.link import FcuLink

TIMEOUTS = CommandTimeouts(ack_s=0.5, attempts=3, in_progress_s=1.5)


T = TypeVar("T")


async def on_link(url: str, body: Callable[[CommandExecutor], Awaitable[T]]) -> T:
    """Run ``body`` with an executor on a live FcuLink to ``url``, telemetry flowing."""
    link = FcuLink(url)
    running = asyncio.create_task(link.run())
    try:
        await asyncio.wait_for(link.wait_identified(), 10)
        while link.latest.get("HOME_POSITION") is None:
            await link.wait_for(lambda m: m.get_type() == "HOME_POSITION", 5)
        return await body(CommandExecutor(link, TIMEOUTS))
    finally:
        running.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await running


@contextlib.contextmanager
def simulated(autopilot: Autopilot) -> Iterator[SimulatorServer]:
    config = SimulatorConfig(
        listen=ListenAddress("tcp", "127.0.0.1", 0), speedup=10.0, autopilot=autopilot
    )
    with serving(config) as (server, _address):
        yield server


def fcu_url(server: SimulatorServer) -> str:
    assert server.address is not None
    return f"tcp:127.0.0.1:{server.address.port}"


SYSID = 5


SET_MESSAGE_INTERVAL = mavlink2.MAV_CMD_SET_MESSAGE_INTERVAL


def sim_config(**overrides: Any) -> SimulatorConfig:
    return SimulatorConfig(
        listen=ListenAddress("tcp", "127.0.0.1", 0), system_id=SYSID, **overrides
    )


class FcuTap(CuttableProxy):
    """TCP between the agent and the flight controller: records what the agent sends, and
    can corrupt (garbage, bad CRCs, truncated frames), silence or cut the other way."""

    def __init__(self, target_port: int) -> None:
        super().__init__(("127.0.0.1", target_port))
        self.corrupt_every = 0  # frames between injections; 0 passes everything intact
        self.injections = 0
        self._silent = threading.Event()
        self._changed = threading.Condition()
        self._from_agent: list[Any] = []

    def silence(self) -> None:
        """Keep the connection but let nothing through, as a radio out of range."""
        self._silent.set()

    def speak(self) -> None:
        self._silent.clear()

    def interval_requests(self) -> int:
        with self._changed:
            return sum(1 for m in self._from_agent if _is_set_interval(m))

    def wait_for_interval_requests(self, count: int, timeout_s: float) -> None:
        with self._changed:
            if not self._changed.wait_for(lambda: self.interval_requests() >= count, timeout_s):
                raise AssertionError(
                    f"the agent sent {self.interval_requests()} SET_MESSAGE_INTERVALs "
                    f"within {timeout_s} s, expected {count}"
                )

    def filters(self) -> tuple[Filter, Filter]:
        return self._uplink(), self._downlink()

    def _uplink(self) -> Filter:
        parser = _robust_parser()

        def record(data: bytes) -> bytes:
            if self._silent.is_set():
                return b""
            decoded = [m for m in parser.parse_buffer(data) or [] if m.get_type() != "BAD_DATA"]
            with self._changed:
                self._from_agent += decoded
                self._changed.notify_all()
            return data

        return record

    def _downlink(self) -> Filter:
        parser = _robust_parser()
        frames = 0

        def reframe_and_spoil(data: bytes) -> bytes:
            nonlocal frames
            if self._silent.is_set():
                return b""
            out = bytearray()
            for message in parser.parse_buffer(data) or []:
                frame = bytes(message.get_msgbuf())
                out += frame
                frames += 1
                if self.corrupt_every and frames % self.corrupt_every == 0:
                    out += _spoiled(frame)
                    self.injections += 1
            return bytes(out)

        return reframe_and_spoil


def _spoiled(frame: bytes) -> bytes:
    """Garbage, the frame with a bad CRC, then the frame cut short (it swallows the start
    of the next frame, as a dropped byte on a serial line does)."""
    bad_crc = bytearray(frame)
    bad_crc[-1] ^= 0xFF
    return b"\x00\x13line noise\x37" + bytes(bad_crc) + frame[: len(frame) // 2]


def _robust_parser() -> Any:
    parser = mavlink2.MAVLink(None)
    parser.robust_parsing = True
    return parser


def _is_set_interval(message: Any) -> bool:
    return bool(message.get_type() == "COMMAND_LONG" and message.command == SET_MESSAGE_INTERVAL)


def state_of(vehicle: str) -> Callable[[dict[str, dict[str, Any]]], dict[str, Any]]:
    def state(vehicles: dict[str, dict[str, Any]]) -> dict[str, Any]:
        summary = vehicles.get(vehicle) or {}
        return dict(summary.get("state") or {}) if summary.get("connected") else {}

    return state
