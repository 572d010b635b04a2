"""`gcs-agent lidar-probe DEVICE`: find which LIDAR is on a port, before flying.

For each family in turn, at each of its usual baud rates, the probe opens the port,
sends that family's stop and start commands (an LDROBOT sensor needs none: it sends from
power-up) and listens. A family is recognised only by bytes its format vouches for: a
Slamtec sensor by its answer descriptor to the scan command (its standard nodes carry no
checksum, so noise could pass for them), a YDLIDAR by checksummed packets, an LDROBOT by
CRC-checked packets. Once found, it listens until a whole turn has come and prints the
model (where the sensor says it), the health, the points per second, the turn, and the
settings the agent needs.

``tcp://HOST:PORT`` probes the simulator's LIDAR the same way (baud rates do not apply).
"""

from __future__ import annotations

import argparse
import contextlib
import socket
import sys
import time
from dataclasses import dataclass, field
from typing import Protocol

from vehicle_agents.sensors.lidar import ldlidar, rplidar, ydlidar
from vehicle_agents.sensors.lidar.common import DeviceInfo, Health, Packet, StreamParser
from vehicle_agents.sensors.lidar.models import MODELS, start_commands, stop_command

BAUDS = {
    "rplidar": (115200, 256000, 460800, 1000000),
    "ydlidar": (230400, 128000, 115200, 512000),
    "ldlidar": (230400, 921600),
}
# The model whose commands each family's attempt sends (the commands are the family's).
ATTEMPT_MODEL = {"rplidar": "rplidar-a1", "ydlidar": "ydlidar-tmini-pro", "ldlidar": "ld06"}
LISTEN_S = 1.5  # long enough for a sensor to answer and send a few hundred points
TURN_WAIT_S = 3.0  # after recognition, for a whole turn (a slow head turns at 5 Hz)
MIN_POINTS = 50
RATE_WINDOW_S = 1.0  # the points per second are counted over at least this
SECTORS = 12


class Link(Protocol):
    def write(self, data: bytes) -> None: ...

    def read(self) -> bytes: ...

    def close(self) -> None: ...


class _TcpLink:
    def __init__(self, url: str) -> None:
        host, _, port = url.removeprefix("tcp://").rpartition(":")
        self._sock = socket.create_connection((host, int(port)), timeout=2.0)
        self._sock.settimeout(0.05)

    def write(self, data: bytes) -> None:
        self._sock.sendall(data)

    def read(self) -> bytes:
        try:
            return self._sock.recv(4096)
        except TimeoutError:
            return b""

    def close(self) -> None:
        self._sock.close()


class _SerialLink:
    def __init__(self, device: str, baud: int, family: str) -> None:
        import serial  # type: ignore[import-untyped]  # pyserial: in the agent's base set

        self._port = serial.Serial(device, baud, timeout=0.05)
        if family == "rplidar":
            with contextlib.suppress(OSError):  # a bare UART has no DTR line
                self._port.dtr = False  # Slamtec's USB adapter runs the motor while low

    def write(self, data: bytes) -> None:
        self._port.write(data)

    def read(self) -> bytes:
        return bytes(self._port.read(4096))

    def close(self) -> None:
        self._port.close()


@dataclass
class ProbeResult:
    family: str
    baud: int | None
    model_hint: str
    info: DeviceInfo | None
    health: Health | None
    points_per_s: float
    turn_hz: float | None
    turn: list[tuple[float, int]] = field(default_factory=list)
    drops: dict[str, int] = field(default_factory=dict)


def _parser(family: str) -> StreamParser:
    if family == "rplidar":
        return rplidar.RplidarParser(scan=None)  # only after the sensor's own answer
    if family == "ydlidar":
        return ydlidar.YdlidarParser(sample_bytes=None)
    return ldlidar.LdlidarParser()


def _recognised(family: str, parser: StreamParser) -> bool:
    stats = parser.stats
    if stats.points < MIN_POINTS:
        return False
    if family == "rplidar" and isinstance(parser, rplidar.RplidarParser):
        # an answer announced the scan, and the nodes keep their check bits
        return parser.scan is not None and stats.drops["bad_check_bits"] < stats.points // 10
    return stats.packets > 4 * (stats.drops["bad_checksum"] + stats.drops["bad_crc"])


def _attempt(link: Link, family: str, baud: int | None) -> ProbeResult | None:
    model = MODELS[ATTEMPT_MODEL[family]]
    parser = _parser(family)
    stop = stop_command(model)
    if stop:
        link.write(stop)
        time.sleep(0.05)
        link.read()  # a scan left running
    for command in start_commands(model):
        link.write(command)
        time.sleep(0.05)
    packets: list[Packet] = []
    recognised = False
    first: tuple[float, int] | None = None  # the first data's arrival, and its points
    last_at = 0.0
    deadline = time.monotonic() + LISTEN_S
    while time.monotonic() < deadline:
        data = link.read()
        if data:
            packets += parser.feed(data)
            last_at = time.monotonic()
            if first is None:
                first = (last_at, parser.stats.points)
        if not recognised and _recognised(family, parser):
            recognised = True
            deadline = time.monotonic() + TURN_WAIT_S  # now wait for a whole turn
        if (
            recognised
            and first is not None
            and last_at - first[0] >= RATE_WINDOW_S
            and sum(p.zero for p in packets) >= 2
        ):
            break
    if not _recognised(family, parser):
        return None
    assert first is not None
    elapsed = last_at - first[0]
    turn, hz = _first_turn(packets)
    hint = _model_hint(family, parser)
    if stop:
        with contextlib.suppress(OSError):
            link.write(stop)
    return ProbeResult(
        family=family,
        baud=baud,
        model_hint=hint,
        info=parser.info,
        health=parser.health,
        # the points after the first read, over the time since it
        points_per_s=(parser.stats.points - first[1]) / elapsed if elapsed > 0 else 0.0,
        turn_hz=hz,
        turn=turn,
        drops=dict(parser.stats.drops),
    )


def _first_turn(packets: list[Packet]) -> tuple[list[tuple[float, int]], float | None]:
    starts = [i for i, p in enumerate(packets) if p.zero]
    if len(starts) < 2:
        return [], None
    turn = [
        (a, d)
        for p in packets[starts[0] : starts[1]]
        for a, d in zip(p.angles_deg, p.distances_mm, strict=True)
    ]
    hz = next((p.scan_hz for p in packets if p.scan_hz), None)
    return turn, hz


def _model_hint(family: str, parser: StreamParser) -> str:
    if family == "ldlidar":
        return "ld06 or ld19 (230400 baud), stl27l (921600 baud)"
    if family == "ydlidar" and isinstance(parser, ydlidar.YdlidarParser):
        if parser.sample_bytes == 3:
            return "ydlidar-tmini-pro (3-byte samples)"
        return "ydlidar-x4 or ydlidar-x2 (2-byte samples, intercept correction) or ydlidar-g4"
    name = parser.info.name if parser.info else ""
    return {"RPLIDAR A1": "rplidar-a1", "RPLIDAR A2": "rplidar-a2", "RPLIDAR A3": "rplidar-a3"}.get(
        name, "rplidar-c1, -s1 or -s2 (by the baud rate)"
    )


def probe(
    device: str, families: tuple[str, ...] = ("rplidar", "ydlidar", "ldlidar")
) -> ProbeResult | None:
    """The first family (and baud rate) whose bytes come back valid; None if none does."""
    for family in families:
        bauds: tuple[int | None, ...] = (None,) if device.startswith("tcp://") else BAUDS[family]
        for baud in bauds:
            link: Link = _TcpLink(device) if baud is None else _SerialLink(device, baud, family)
            try:
                result = _attempt(link, family, baud)
            finally:
                link.close()
            if result is not None:
                return result
    return None


def describe(result: ProbeResult) -> str:
    lines = [f"family: {result.family}" + (f" at {result.baud} baud" if result.baud else "")]
    if result.info is not None:
        info = result.info
        lines.append(
            f"model: {info.name}, firmware {info.firmware}, hardware {info.hardware}, "
            f"serial {info.serial}"
        )
    lines.append(f"model setting: {result.model_hint}")
    lines.append(f"health: {result.health.text if result.health else 'not reported'}")
    lines.append(f"points per second: {result.points_per_s:.0f}")
    if result.turn_hz:
        lines.append(f"turns per second (the sensor's word): {result.turn_hz:g}")
    drops = ", ".join(f"{k} {v}" for k, v in sorted(result.drops.items())) or "none"
    lines.append(f"dropped: {drops}")
    if not result.turn:
        lines.append("no whole turn within the wait: is the motor turning?")
        return "\n".join(lines)
    returns = [d for _, d in result.turn if d]
    lines.append(
        f"first turn: {len(result.turn)} points, {len(returns)} returns"
        + (f", {min(returns)}..{max(returns)} mm" if returns else "")
    )
    lines.append("nearest return per 30-degree sector (clockwise from the sensor's zero mark):")
    nearest: list[int | None] = [None] * SECTORS
    for angle, distance in result.turn:
        sector = int(angle // (360 / SECTORS)) % SECTORS
        if distance and (nearest[sector] is None or distance < (nearest[sector] or 0)):
            nearest[sector] = distance
    lines.append(
        "  "
        + "  ".join(
            f"{s * 30:3d}: {'-' if d is None else f'{d / 1000:.2f} m'}"
            for s, d in enumerate(nearest)
        )
    )
    return "\n".join(lines)


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(
        prog="gcs-agent lidar-probe",
        description="Find the LIDAR on a serial port: its family, baud rate, model, health, "
        "points per second and a first turn.",
    )
    parser.add_argument("device", help="a serial device (/dev/ttyUSB0) or tcp://HOST:PORT")
    parser.add_argument(
        "--family",
        action="append",
        choices=sorted(BAUDS),
        help="try only this family (repeatable; default: all)",
    )
    args = parser.parse_args(argv)
    families = tuple(args.family) if args.family else ("rplidar", "ydlidar", "ldlidar")
    try:
        result = probe(args.device, families)
    except OSError as error:
        print(f"lidar-probe: cannot open {args.device}: {error}", file=sys.stderr)
        return 2
    if result is None:
        print(
            f"lidar-probe: no LIDAR answered on {args.device} ({', '.join(families)}, at "
            "their usual baud rates). Check the power (5 V, enough current for the motor), "
            "TX/RX crossed, and that nothing else holds the port.",
            file=sys.stderr,
        )
        return 1
    print(describe(result))
    return 0
