"""MANUAL_CONTROL in the simulated copter, as ArduCopter takes it: an RC override from
SYSID_MYGCS only, flown in LOITER, lapsing after RC_OVERRIDE_TIME."""

from __future__ import annotations

import math

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from simulator import Copter, CopterMode, MavResult
from simulator.commands.handler import MessageHandler
from simulator.telemetry import TelemetryBuilder
from tests.simulator.test_sim_copter import airborne, run_until


def in_loiter() -> Copter:
    copter = airborne(10.0)
    assert copter.set_mode(CopterMode.LOITER) is MavResult.ACCEPTED
    copter.body.yaw = 0.0  # facing north
    return copter


def test_pitch_forward_flies_north_and_throttle_climbs() -> None:
    copter = in_loiter()
    start_n, start_alt = copter.body.north, copter.body.alt
    for _ in range(75):  # 3 s of sticks at 25 Hz: half forward, throttle full
        copter.manual_control(500, 0, 1000, 0)
        copter.advance(0.04)
    assert copter.body.north - start_n > 5.0
    assert abs(copter.body.east) < 1.0
    assert copter.body.alt - start_alt > 2.0


def test_the_override_lapses_after_rc_override_time() -> None:
    copter = in_loiter()
    copter.manual_control(1000, 0, 500, 0)
    copter.advance(0.5)
    assert copter.overridden_sticks() is not None
    copter.advance(copter.params.rc_override_time)
    assert copter.overridden_sticks() is None
    run_until(copter, lambda c: math.hypot(c.body.vn, c.body.ve) < 0.1, 30)


def test_only_the_configured_gcs_is_obeyed() -> None:
    copter = in_loiter()
    handler = MessageHandler(copter, TelemetryBuilder(copter, boot_epoch_s=0.0), 1)
    # Encoded and parsed back, so the sender's system id is on it as on the wire.
    sender = mavlink2.MAVLink(None, srcSystem=254, srcComponent=191)
    frame = sender.manual_control_encode(1, 1000, 0, 500, 0, 0).pack(sender)
    message = mavlink2.MAVLink(None).parse_char(frame)
    handler.handle(message, streams=None, now=0.0)  # type: ignore[arg-type]
    assert copter.overridden_sticks() is None  # SYSID_MYGCS is 255 by default
    copter.params = type(copter.params)(**{**vars(copter.params), "sysid_mygcs": 254})
    handler.handle(message, streams=None, now=0.0)  # type: ignore[arg-type]
    assert copter.overridden_sticks() == (1000, 0, 500, 0)
