"""MANUAL_CONTROL in the simulated copter, as ArduCopter takes it: an RC override from
SYSID_MYGCS only, flown in LOITER, lapsing after RC_OVERRIDE_TIME."""

from __future__ import annotations

import math

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from gcs.launcher import AGENT_SYSTEM_ID, FleetPlan
from simulator import DEFAULT_HOME, Copter, CopterMode, MavResult, main
from simulator.config import parse_args
from simulator.mavconst import ModeFlag, Px4AutoMode, Px4MainMode
from simulator.mavlink.commands.handler import MessageHandler
from simulator.mavlink.telemetry import TelemetryBuilder
from simulator.params.table import SetOutcome
from simulator.personality.px4 import Px4Personality
from simulator.vehicle import Vehicle
from simulator.vehicles import build_vehicle
from tests.support.copters import airborne, run_until


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


def _stick_input_from_the_agent(copter: Vehicle) -> bool:
    """Whether ``copter`` takes a MANUAL_CONTROL the agent (system 254) sends."""
    handler = MessageHandler(copter, TelemetryBuilder(copter, boot_epoch_s=0.0), 1)
    sender = mavlink2.MAVLink(None, srcSystem=254, srcComponent=191)
    frame = sender.manual_control_encode(1, 1000, 0, 500, 0, 0).pack(sender)
    handler.handle(mavlink2.MAVLink(None).parse_char(frame), streams=None, now=0.0)  # type: ignore[arg-type]
    return copter.overridden_sticks() is not None


@pytest.mark.parametrize("frame", ["quad", "rover"])
def test_the_demo_sets_its_vehicles_up_for_the_agent(frame: str) -> None:
    """`gcs demo` sets SYSID_MYGCS to the agent's id on the simulator's command line, as
    an owner sets it on a real aircraft; a simulator started without it keeps
    ArduPilot's 255 and ignores the agent, as the real one would."""
    plan = FleetPlan(frames=(frame,))
    assert plan.vehicle_sim_args(0)[-2:] == ["--param", f"SYSID_MYGCS={AGENT_SYSTEM_ID}"]
    demo = build_vehicle(parse_args(plan.vehicle_sim_args(0)))
    assert demo.param_table.get("SYSID_MYGCS") == 254
    assert _stick_input_from_the_agent(demo)
    unset = build_vehicle(parse_args(["--frame", frame]))
    assert unset.param_table.get("SYSID_MYGCS") == 255
    assert not _stick_input_from_the_agent(unset)
    # PX4 checks no sender id, but its deadman hold must be exempt from its
    # manual-control-loss failsafe (COM_RCL_EXCEPT bit 1, Hold).
    px4 = FleetPlan(autopilots=("px4",)).vehicle_sim_args(0)
    assert px4[-2:] == ["--param", "COM_RCL_EXCEPT=2"]
    assert build_vehicle(parse_args(px4)).param_table.get("COM_RCL_EXCEPT") == 2
    assert "--param" not in FleetPlan(gcs_configured=False).vehicle_sim_args(0)


@pytest.mark.parametrize(
    ("argv", "error"),
    [
        (["--param", "NO_SUCH_PARAM=1"], "no such parameter"),
        (["--param", "SYSID_MYGCS=300"], "out of its range"),
        (["--autopilot", "px4", "--param", "SYSID_MYGCS=254"], "no such parameter"),
    ],
)
def test_a_boot_parameter_the_vehicle_cannot_take_stops_the_simulator(
    argv: list[str], error: str, caplog: pytest.LogCaptureFixture
) -> None:
    assert main(argv) == 2
    assert error in caplog.text


def test_a_boot_parameter_must_be_name_equals_value(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--param", "SYSID_MYGCS"]) == 2
    assert "expected NAME=VALUE" in capsys.readouterr().err


def test_arducopter_loiter_flies_the_transmitter_throttle_until_overridden() -> None:
    """SITL's transmitter sits at minimum throttle: LOITER entered before any override
    descends (the 2.8 m a late first frame cost); centred sticks at mid throttle hold."""
    copter = in_loiter()
    start_alt = copter.body.alt
    copter.advance(2.0)
    assert start_alt - copter.body.alt > 1.5
    copter = in_loiter()
    start_alt = copter.body.alt
    for _ in range(50):  # 2 s of centred sticks at 25 Hz
        copter.manual_control(0, 0, 500, 0)
        copter.advance(0.04)
    assert abs(copter.body.alt - start_alt) < 0.1


def px4_hovering() -> Copter:
    """A PX4 copter hovering at 10 m in Hold (AUTO.LOITER)."""
    px4 = Copter(DEFAULT_HOME, personality=Px4Personality())
    assert px4.set_mode(CopterMode.GUIDED) is MavResult.ACCEPTED
    assert px4.arm() is MavResult.ACCEPTED
    assert px4.takeoff(10.0) is MavResult.ACCEPTED
    run_until(px4, lambda c: abs(c.body.alt - 10.0) < 0.05 and abs(c.body.vd) < 0.05, 60)
    assert px4_mode(px4, Px4MainMode.AUTO, Px4AutoMode.LOITER) is MavResult.ACCEPTED
    px4.drain_texts()
    return px4


def px4_mode(copter: Copter, main_mode: int, sub_mode: int = 0) -> MavResult:
    return copter.request_mode(ModeFlag.CUSTOM_MODE_ENABLED, main_mode, sub_mode)


def test_px4_takes_position_mode_in_the_air_only_with_manual_input() -> None:
    """Commander refuses POSCTL (TEMPORARILY_REJECTED) until manual input has come within
    COM_RC_LOSS_T; on the ground it is taken; MAVLink input comes from any sender."""
    copter = px4_hovering()
    assert px4_mode(copter, Px4MainMode.POSCTL) is MavResult.TEMPORARILY_REJECTED
    assert "No manual control input" in [text.text for text in copter.drain_texts()]
    assert _stick_input_from_the_agent(copter)  # PX4 checks no SYSID_MYGCS
    assert px4_mode(copter, Px4MainMode.POSCTL) is MavResult.ACCEPTED
    ground = Copter(DEFAULT_HOME, personality=Px4Personality())
    assert px4_mode(ground, Px4MainMode.POSCTL) is MavResult.ACCEPTED


@pytest.mark.parametrize(("exempt", "mode_after"), [(0, CopterMode.RTL), (2, CopterMode.LOITER)])
def test_px4_manual_control_loss_returns_unless_hold_is_exempt(
    exempt: int, mode_after: CopterMode
) -> None:
    """Manual input that stops is lost after COM_RC_LOSS_T; COM_FAIL_ACT_T later PX4 flies
    NAV_RCL_ACT (Return) unless COM_RCL_EXCEPT exempts the mode (bit 1: Hold)."""
    copter = px4_hovering()
    assert copter.set_param("COM_RCL_EXCEPT", exempt) is SetOutcome.STORED
    copter.manual_control(0, 0, 500, 0)
    assert px4_mode(copter, Px4MainMode.POSCTL) is MavResult.ACCEPTED
    copter.advance(0.5)
    assert px4_mode(copter, Px4MainMode.AUTO, Px4AutoMode.LOITER) is MavResult.ACCEPTED
    copter.advance(5.0)  # COM_RC_LOSS_T 0.5 s + COM_FAIL_ACT_T 5 s from the last input
    assert copter.mode is CopterMode.LOITER
    copter.advance(0.2)
    assert copter.mode is mode_after
