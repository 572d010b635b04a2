"""The LIDAR models the agent reads on a serial port: each one's family, wire format,
default baud rate and wiring (the sensor table in docs/reference.md is this table), and how to start
and stop it."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from vehicle_agents.sensors.lidar import ldlidar, rplidar, ydlidar
from vehicle_agents.sensors.lidar.common import StreamParser

Family = Literal["rplidar", "ydlidar", "ldlidar"]


@dataclass(frozen=True)
class Model:
    name: str
    family: Family
    baud: int
    wire: str  # the wire format, as docs/reference.md and the simulator's --lidar-format name it
    wiring: str
    sample_bytes: int | None = None  # YDLIDAR: 2 or 3
    intercept: bool = False  # YDLIDAR X2/X4: the manual's angle correction
    motor_pwm: bool = False  # RPLIDAR A2/A3: SET_MOTOR_PWM starts the motor


_SLAMTEC_USB = "Slamtec's USB adapter (CP2102; DTR drives the motor), or 5 V, GND and 3.3 V UART"
_YD_USB = "YDLIDAR's USB adapter board, or 5 V, GND and 3.3 V UART TX/RX"
_LD_UART = (
    "5 V, GND and the sensor's TX to the computer's RX (3.3 V UART); "
    "PWM to GND for the built-in speed"
)
MODELS: dict[str, Model] = {
    model.name: model
    for model in (
        Model("rplidar-a1", "rplidar", 115200, "rplidar", _SLAMTEC_USB),
        Model(
            "rplidar-a2",
            "rplidar",
            115200,
            "rplidar",
            _SLAMTEC_USB + " (A2M12: 256000 baud)",
            motor_pwm=True,
        ),
        Model("rplidar-a3", "rplidar", 256000, "rplidar", _SLAMTEC_USB, motor_pwm=True),
        Model(
            "rplidar-c1",
            "rplidar",
            460800,
            "rplidar",
            "its USB-C adapter, or 5 V, GND and 3.3 V UART",
        ),
        Model(
            "rplidar-s1",
            "rplidar",
            256000,
            "rplidar",
            "its USB adapter, or 5 V, GND and 3.3 V UART",
        ),
        Model(
            "rplidar-s2",
            "rplidar",
            1000000,
            "rplidar",
            "its USB adapter, or 5 V, GND and 3.3 V UART",
        ),
        Model(
            "ydlidar-x2", "ydlidar", 115200, "ydlidar-x4", _YD_USB, sample_bytes=2, intercept=True
        ),
        Model(
            "ydlidar-x4", "ydlidar", 128000, "ydlidar-x4", _YD_USB, sample_bytes=2, intercept=True
        ),
        Model("ydlidar-g4", "ydlidar", 230400, "ydlidar-g4", _YD_USB, sample_bytes=2),
        Model("ydlidar-tmini-pro", "ydlidar", 230400, "ydlidar", _YD_USB, sample_bytes=3),
        Model("ld06", "ldlidar", 230400, "ld06", _LD_UART),
        Model("ld19", "ldlidar", 230400, "ld06", _LD_UART),
        Model("stl27l", "ldlidar", 921600, "ld06", _LD_UART),
    )
}
DEFAULT_MODEL = "ydlidar-tmini-pro"


def model_named(name: str) -> Model:
    try:
        return MODELS[name]
    except KeyError:
        raise ValueError(
            f"unknown LIDAR model {name!r}; known: {', '.join(sorted(MODELS))}"
        ) from None


def make_parser(model: Model) -> StreamParser:
    if model.family == "rplidar":
        return rplidar.RplidarParser()
    if model.family == "ydlidar":
        return ydlidar.YdlidarParser(model.sample_bytes, model.intercept)
    return ldlidar.LdlidarParser()


def stop_command(model: Model) -> bytes:
    if model.family == "rplidar":
        return rplidar.request(rplidar.STOP)
    if model.family == "ydlidar":
        return ydlidar.STOP_SCAN
    return b""  # an LDROBOT sensor takes no commands


def start_commands(model: Model, scan_mode: int = 0) -> list[bytes]:
    """The commands that start a scan once the sensor is stopped, to be sent a moment
    apart (a sensor answers one before it reads the next): the information and health
    questions first, so that their answers come before the samples. ``scan_mode``, RPLIDAR
    only: 0 the standard scan, N an express scan in working mode N (the sensor's answer
    says which capsule it sends)."""
    if model.family == "rplidar":
        scan = rplidar.request(rplidar.SCAN) if scan_mode == 0 else rplidar.express_scan(scan_mode)
        motor = [rplidar.motor_pwm(rplidar.DEFAULT_PWM)] if model.motor_pwm else []
        info = rplidar.request(rplidar.GET_INFO)
        return [info, rplidar.request(rplidar.GET_HEALTH), *motor, scan]
    if model.family == "ydlidar":
        return [ydlidar.GET_INFO, ydlidar.GET_HEALTH, ydlidar.START_SCAN]
    return []
