"""A flight controller's stream, simulated: 200 MAVLink messages/s over TCP to each client,
its parameters on request, and a UDP sink that counts what a forward sends on."""

from __future__ import annotations

import asyncio
import math
import socket
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

# ArduCopter-like rates (Hz); they add up to 200 messages/s.
STREAM_HZ: dict[str, float] = {
    "ATTITUDE": 50,
    "RAW_IMU": 25,
    "GLOBAL_POSITION_INT": 25,
    "VFR_HUD": 20,
    "LOCAL_POSITION_NED": 20,
    "SERVO_OUTPUT_RAW": 10,
    "RC_CHANNELS": 10,
    "SCALED_PRESSURE": 10,
    "GPS_RAW_INT": 10,
    "SYS_STATUS": 5,
    "BATTERY_STATUS": 5,
    "EKF_STATUS_REPORT": 5,
    "VIBRATION": 3,
    "SYSTEM_TIME": 1,
    "HEARTBEAT": 1,
}
RATE = sum(STREAM_HZ.values())
TICK_S = 0.005
PARAMS = {f"BENCH_P{i:02d}": float(i) for i in range(40)} | {"SYSID_THISMAV": 1.0}
MAX_CLIENT_BACKLOG = 1 << 20  # bytes queued for a client that does not read: drop beyond


def build(kind: str, t: float, boot: float) -> Any:
    """One message of ``kind`` with values that move, as a vehicle in flight sends them."""
    ms = int((t - boot) * 1000) & 0xFFFFFFFF  # time_boot_ms
    us = int((t - boot) * 1e6)  # time_usec (uint64)
    s = math.sin(t)
    m = mavlink2
    match kind:
        case "HEARTBEAT":
            return m.MAVLink_heartbeat_message(
                m.MAV_TYPE_QUADROTOR,
                m.MAV_AUTOPILOT_ARDUPILOTMEGA,
                m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | m.MAV_MODE_FLAG_SAFETY_ARMED,
                5,
                m.MAV_STATE_ACTIVE,
                3,
            )
        case "ATTITUDE":
            return m.MAVLink_attitude_message(ms, 0.05 * s, -0.03 * s, 1.2 + 0.1 * s, 0, 0, 0.01)
        case "RAW_IMU":
            return m.MAVLink_raw_imu_message(us, 10, -5, -1000, 1, 2, 3, 200, 100, -400)
        case "GLOBAL_POSITION_INT":
            return m.MAVLink_global_position_int_message(
                ms, int(-353632620 + 500 * s), 1491652370, 614000, 30000, 150, 20, -10, 9000
            )
        case "VFR_HUD":
            return m.MAVLink_vfr_hud_message(0.0, 1.8, 90, 45, 614.0, -0.1)
        case "LOCAL_POSITION_NED":
            return m.MAVLink_local_position_ned_message(ms, 5.0 * s, 2.0, -30.0, 1.5, 0.2, -0.1)
        case "SERVO_OUTPUT_RAW":
            return m.MAVLink_servo_output_raw_message(us & 0xFFFFFFFF, 0, *([1500] * 8))
        case "RC_CHANNELS":
            return m.MAVLink_rc_channels_message(ms, 16, *([1500] * 18), 255)
        case "SCALED_PRESSURE":
            return m.MAVLink_scaled_pressure_message(ms, 1005.2, 0.1, 2150)
        case "GPS_RAW_INT":
            return m.MAVLink_gps_raw_int_message(
                us, 3, -353632620, 1491652370, 614000, 80, 120, 180, 9000, 14
            )
        case "SYS_STATUS":
            sensors = 0x0321FC3F
            return m.MAVLink_sys_status_message(
                sensors, sensors, sensors, 250, 15800, 1250, 78, 0, 0, 0, 0, 0, 0
            )
        case "BATTERY_STATUS":
            return m.MAVLink_battery_status_message(
                0, 1, 1, 3000, [3950] * 4 + [65535] * 6, 1250, 2100, 23000, 78
            )
        case "EKF_STATUS_REPORT":
            return m.MAVLink_ekf_status_report_message(0x3FF, 0.1, 0.1, 0.05, 0.02, 0.0)
        case "VIBRATION":
            return m.MAVLink_vibration_message(us, 4.0, 4.5, 6.0, 0, 0, 0)
        case "SYSTEM_TIME":
            return m.MAVLink_system_time_message(int(t * 1e6), ms)
    raise ValueError(kind)


@dataclass
class Client:
    writer: asyncio.StreamWriter
    encoder: Any = field(
        default_factory=lambda: mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    )
    parser: Any = field(default_factory=lambda: mavlink2.MAVLink(None))
    sent: int = 0
    dropped: int = 0

    def send(self, message: Any) -> None:
        transport = self.writer.transport
        if transport.is_closing():
            return
        if transport.get_write_buffer_size() > MAX_CLIENT_BACKLOG:
            self.dropped += 1
            return
        self.writer.write(message.pack(self.encoder))
        self.sent += 1


class MavlinkSource:
    """A TCP server that streams the mix to every client and answers like a vehicle."""

    def __init__(self) -> None:
        self.clients: list[Client] = []
        self.boot = time.time()
        self.port = 0

    async def serve(self, ready: asyncio.Event) -> None:
        server = await asyncio.start_server(self._client, "127.0.0.1", 0)
        self.port = server.sockets[0].getsockname()[1]
        ready.set()
        async with server:
            next_due = {
                kind: time.monotonic() + i / len(STREAM_HZ) for i, kind in enumerate(STREAM_HZ)
            }
            while True:
                now = time.monotonic()
                for kind, hz in STREAM_HZ.items():
                    while next_due[kind] <= now:
                        message = build(kind, time.time(), self.boot)
                        for client in list(self.clients):
                            client.send(message)
                        next_due[kind] += 1 / hz
                await asyncio.sleep(TICK_S)

    async def _client(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        client = Client(writer)
        self.clients.append(client)
        try:
            while data := await reader.read(4096):
                for message in client.parser.parse_buffer(data) or []:
                    for reply in self._answer(message):
                        client.send(reply)
        except (ConnectionError, OSError):
            pass
        finally:
            self.clients.remove(client)
            writer.close()

    def _answer(self, message: Any) -> list[Any]:
        m = mavlink2
        kind = message.get_type()
        sender = message.get_srcSystem(), message.get_srcComponent()
        if kind == "COMMAND_LONG":
            return [
                m.MAVLink_command_ack_message(message.command, m.MAV_RESULT_ACCEPTED, 0, 0, *sender)
            ]
        if kind == "PARAM_REQUEST_LIST":
            return [self._param(name) for name in PARAMS]
        if kind == "PARAM_REQUEST_READ":
            names = list(PARAMS)
            index = message.param_index
            name = names[index] if 0 <= index < len(names) else message.param_id
            return [self._param(name)] if name in PARAMS else []
        if kind == "MISSION_REQUEST_LIST":
            return [m.MAVLink_mission_count_message(*sender, 0, message.mission_type)]
        return []

    def _param(self, name: str) -> Any:
        names = list(PARAMS)
        return mavlink2.MAVLink_param_value_message(
            name.encode(),
            PARAMS[name],
            mavlink2.MAV_PARAM_TYPE_REAL32,
            len(names),
            names.index(name),
        )


class UdpSink:
    """A GCS that only listens: counts, on a thread of its own, the frames sent to it."""

    def __init__(self) -> None:
        self.socket = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.socket.bind(("127.0.0.1", 0))
        self.socket.settimeout(0.5)
        self.port = self.socket.getsockname()[1]
        self.frames = 0
        threading.Thread(target=self._count, daemon=True).start()

    def _count(self) -> None:
        parser = mavlink2.MAVLink(None)
        while True:
            try:
                data = self.socket.recv(65535)
            except TimeoutError:
                continue
            except OSError:
                return  # closed
            self.frames += len(parser.parse_buffer(data) or [])


def run_source(ready: Callable[[MavlinkSource], None]) -> None:
    """The source on its own event loop, in a daemon thread of the benchmark process."""

    async def main() -> None:
        source = MavlinkSource()
        started = asyncio.Event()
        task = asyncio.create_task(source.serve(started))
        await started.wait()
        ready(source)
        await task

    asyncio.run(main())
