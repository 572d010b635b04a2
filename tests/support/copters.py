"""The simulated copter in this process, stepped by hand: a vehicle in the air, running
it until a condition holds, and a vehicle answering MAVLink commands in memory."""

from __future__ import annotations

from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from simulator import DEFAULT_HOME, Copter, CopterMode, MavResult
from simulator.mavlink.commands import MessageHandler, Reply
from simulator.mavlink.streams import StreamSchedule
from simulator.mavlink.telemetry import DEFAULT_RATES_HZ, TelemetryBuilder


def texts(copter: Copter) -> list[str]:
    return [text.text for text in copter.drain_texts()]


def run_until(copter: Copter, condition: object, limit_s: float, step_s: float = 0.1) -> float:
    """Advance until ``condition(copter)`` holds; returns the sim time it took."""
    assert callable(condition)
    start = copter.time_s
    while not condition(copter):
        if copter.time_s - start > limit_s:
            raise AssertionError(f"condition not met within {limit_s} s of sim time")
        copter.advance(step_s)
    return copter.time_s - start


def airborne(altitude: float = 10.0) -> Copter:
    """A copter hovering at ``altitude`` m above home in GUIDED."""
    copter = Copter(DEFAULT_HOME)
    assert copter.set_mode(CopterMode.GUIDED) is MavResult.ACCEPTED
    assert copter.arm() is MavResult.ACCEPTED
    assert copter.takeoff(altitude) is MavResult.ACCEPTED
    run_until(copter, lambda c: abs(c.body.alt - altitude) < 0.05 and abs(c.body.vd) < 0.05, 60)
    copter.drain_texts()
    return copter


SYSID = 3


GCS_SYSID, GCS_COMPID = 255, 190


class Vehicle:
    """A copter with its handler, fed messages as if they came off the wire."""

    def __init__(self) -> None:
        self.copter = Copter(DEFAULT_HOME)
        self.telemetry = TelemetryBuilder(self.copter, boot_epoch_s=1_700_000_000.0)
        self.handler = MessageHandler(self.copter, self.telemetry, SYSID)
        self.streams = StreamSchedule(DEFAULT_RATES_HZ, now=0.0)
        self._gcs = mavlink2.MAVLink(None, srcSystem=GCS_SYSID, srcComponent=GCS_COMPID)
        self._parser = mavlink2.MAVLink(None)

    def send(self, message: Any) -> list[Reply]:
        [decoded] = self._parser.parse_buffer(message.pack(self._gcs))
        return self.handler.handle(decoded, self.streams, now=0.0)

    def command(self, command: int, *params: float, target: int = SYSID) -> list[Reply]:
        padded = [*params] + [0.0] * (7 - len(params))
        return self.send(mavlink2.MAVLink_command_long_message(target, 1, command, 0, *padded))

    def command_int(
        self, command: int, frame: int, params: list[float], x: int, y: int, z: float
    ) -> list[Reply]:
        padded = [*params] + [0.0] * (4 - len(params))
        return self.send(
            mavlink2.MAVLink_command_int_message(SYSID, 1, frame, command, 0, 0, *padded, x, y, z)
        )

    def mode(self) -> CopterMode:
        return self.copter.mode

    def fly(self, altitude: float = 10.0) -> None:
        self.copter.set_mode(CopterMode.GUIDED)
        self.copter.arm()
        self.copter.takeoff(altitude)
        self.copter.advance(25.0)
        self.copter.drain_texts()


def ack_of(replies: list[Reply]) -> Any:
    acks = [r.message for r in replies if r.message.get_type() == "COMMAND_ACK"]
    assert len(acks) == 1, replies
    return acks[0]


def kinds(replies: list[Reply]) -> list[str]:
    return [r.message.get_type() for r in replies]
