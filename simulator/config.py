"""Command-line settings of the simulator."""

from __future__ import annotations

import argparse
import logging
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

from common.geodesy import GeoPoint
from protocol.photos import CameraIntrinsics, parse_camera_model
from simulator.clock import MAX_SPEEDUP
from simulator.wire.formats import LIDAR_FORMATS

# ArduPilot's SITL home, CMAC (Canberra Model Aircraft Club).
DEFAULT_HOME = GeoPoint(-35.363262, 149.165237, 584.0)

Scheme = Literal["tcp", "udp"]
# What is simulated: a quadcopter or a wheeled rover (as SITL's --frame), and which
# autopilot the quadcopter plays (the rover is always ArduRover).
Frame = Literal["quad", "rover"]
Autopilot = Literal["ardupilot", "px4"]
# How SET_MESSAGE_INTERVAL is answered: as ArduPilot 4 does, or as an old flight
# controller that refuses it (COMMAND_ACK UNSUPPORTED) or drops it (no COMMAND_ACK).
MessageIntervalSupport = Literal["supported", "unsupported", "silent"]
# GPS_FIX_TYPE of the optional second receiver (GPS2_RAW), by --gps2 name.
GPS2_FIX_TYPES = {"3d": 3, "dgps": 4, "rtk-float": 5, "rtk-fixed": 6}


@dataclass(frozen=True)
class ListenAddress:
    """``tcp:HOST:PORT`` (a server, like SITL's port 5760) or ``udp:HOST:PORT`` (bound)."""

    scheme: Scheme
    host: str
    port: int

    @classmethod
    def parse(cls, text: str) -> ListenAddress:
        scheme, sep, rest = text.partition(":")
        host, sep2, port_text = rest.rpartition(":")
        if not sep or not sep2 or scheme not in ("tcp", "udp"):
            raise ValueError(f"expected tcp:HOST:PORT or udp:HOST:PORT, got {text!r}")
        host = host.removeprefix("[").removesuffix("]") or "0.0.0.0"
        try:
            port = int(port_text)
        except ValueError:
            raise ValueError(f"bad port in {text!r}") from None
        if not 0 <= port <= 65535:
            raise ValueError(f"port out of range in {text!r}")
        return cls("tcp" if scheme == "tcp" else "udp", host, port)

    def __str__(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"{self.scheme}:{host}:{self.port}"


@dataclass(frozen=True)
class SimulatorConfig:
    listen: ListenAddress = field(default_factory=lambda: ListenAddress("tcp", "127.0.0.1", 5760))
    system_id: int = 1
    home: GeoPoint = DEFAULT_HOME
    speedup: float = 1.0
    log_level: str = "INFO"
    gps2_fix: int | None = None  # a second GPS with this GPS_FIX_TYPE; None: just one GPS
    message_interval: MessageIntervalSupport = "supported"
    frame: Frame = "quad"
    autopilot: Autopilot = "ardupilot"
    # A 2-D LIDAR whose serial bytes are served on this TCP address; None: no LIDAR.
    lidar: ListenAddress | None = None
    lidar_rate_hz: float = 10.0
    lidar_format: str = "ydlidar"  # the wire format: simulator/wire/formats.py's LIDAR_FORMATS
    scene: Path | None = None  # obstacles (simulator/world/obstacles.py); None: the default yard
    # The camera's photos served over HTTP on this TCP address; None: CAMERA_FEEDBACK only.
    camera: ListenAddress | None = None
    # The camera as a MAVLink camera component (CAMERA_IMAGE_CAPTURED with the photo
    # server's address of each shot), beside the autopilot's own camera messages.
    camera_component: bool = False
    # The camera writes each shot's rendered photo into this folder; None: it does not.
    camera_folder: Path | None = None
    # The camera the component's and the folder's photos are rendered with.
    camera_model: CameraIntrinsics | None = None
    # Where the camera's synthetic ground is laid (its origin and elevation); None: home.
    # Simulators of one fleet share it, so that their photos show one world.
    ground: GeoPoint | None = None
    # Parameters set at boot (MAVLink names and units), as SITL's --defaults file sets
    # them: the vehicle as its owner configured it, e.g. SYSID_MYGCS for the GCS in use.
    params: tuple[tuple[str, float], ...] = ()

    def __post_init__(self) -> None:
        if not 1 <= self.system_id <= 255:
            raise ValueError(f"system id must be 1..255, got {self.system_id}")
        if not 0.0 < self.speedup <= MAX_SPEEDUP:
            raise ValueError(f"speed-up must be > 0 and <= {MAX_SPEEDUP:g}, got {self.speedup}")
        if self.frame == "rover" and self.autopilot != "ardupilot":
            raise ValueError("the rover is simulated as ArduRover only (--autopilot ardupilot)")
        if self.lidar is not None and self.lidar.scheme != "tcp":
            raise ValueError("the LIDAR's bytes are served over TCP only (--lidar tcp:HOST:PORT)")
        if self.camera is not None and self.camera.scheme != "tcp":
            raise ValueError("the camera's photos are served over HTTP (--camera tcp:HOST:PORT)")
        if self.lidar_format not in LIDAR_FORMATS:
            raise ValueError(
                f"LIDAR format must be one of {', '.join(LIDAR_FORMATS)}, got {self.lidar_format}"
            )
        if self.camera_component and self.camera is None:
            raise ValueError(
                "a MAVLink camera component gives its photos' HTTP address: it needs the "
                "photo server (--camera tcp:HOST:PORT)"
            )
        if (self.camera_component or self.camera_folder is not None) and self.camera_model is None:
            raise ValueError(
                "the camera component's and the camera folder's photos are rendered with "
                "--camera-model SW_MM,SH_MM,W_PX,H_PX,F_MM"
            )
        if not 5.0 <= self.lidar_rate_hz <= 12.0:
            raise ValueError(f"LIDAR rate must be 5..12 Hz, got {self.lidar_rate_hz}")
        if self.gps2_fix is not None and not 0 <= self.gps2_fix <= 8:
            raise ValueError(f"GPS2 fix type must be a GPS_FIX_TYPE, 0..8, got {self.gps2_fix}")


def _camera_model(text: str) -> CameraIntrinsics:
    try:
        return parse_camera_model(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def _listen(text: str) -> ListenAddress:
    try:
        return ListenAddress.parse(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def _home(text: str) -> GeoPoint:
    parts = text.split(",")
    try:
        if len(parts) != 3:
            raise ValueError
        lat, lon, alt = (float(part) for part in parts)
        if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0):
            raise ValueError
        return GeoPoint(lat, lon, alt)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected LAT,LON,ALT_MSL in degrees and metres, got {text!r}"
        ) from None


def _param(text: str) -> tuple[str, float]:
    name, sep, value_text = text.partition("=")
    try:
        if not sep or not name:
            raise ValueError
        value = float(value_text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE, got {text!r}") from None
    return name.strip().upper(), value


def _system_id(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = 0
    if not 1 <= value <= 255:
        raise argparse.ArgumentTypeError(f"system id must be 1..255, got {text!r}")
    return value


def _speedup(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = 0.0
    if not 0.0 < value <= MAX_SPEEDUP:
        raise argparse.ArgumentTypeError(f"speed-up must be > 0 and <= {MAX_SPEEDUP:g}")
    return value


def _log_level(text: str) -> str:
    level = text.upper()
    if not isinstance(logging.getLevelName(level), int):
        raise argparse.ArgumentTypeError(f"unknown log level {text!r}")
    return level


def build_parser() -> argparse.ArgumentParser:
    defaults = SimulatorConfig()
    parser = argparse.ArgumentParser(
        prog="gcs sim",
        description="A simulated ArduCopter multirotor speaking MAVLink 2, in place of SITL.",
    )
    parser.add_argument(
        "--listen",
        type=_listen,
        default=defaults.listen,
        metavar="tcp:HOST:PORT|udp:HOST:PORT",
        help=f"TCP server, or UDP socket that answers whoever writes to it "
        f"(default {defaults.listen})",
    )
    parser.add_argument(
        "--system-id",
        type=_system_id,
        default=defaults.system_id,
        metavar="N",
        help="MAVLink system id, 1..255 (default 1)",
    )
    home = defaults.home
    parser.add_argument(
        "--home",
        type=_home,
        default=defaults.home,
        metavar="LAT,LON,ALT_MSL",
        help=f"home position (default {home.lat},{home.lon},{home.alt:g}: ArduPilot's CMAC)",
    )
    parser.add_argument(
        "--speedup",
        type=_speedup,
        default=defaults.speedup,
        metavar="X",
        help=f"sim seconds per wall second, > 0 and <= {MAX_SPEEDUP:g} (default 1)",
    )
    parser.add_argument(
        "--log-level", type=_log_level, default=defaults.log_level, help="default INFO"
    )
    parser.add_argument(
        "--gps2",
        choices=sorted(GPS2_FIX_TYPES),
        help="fit a second GPS (GPS2_RAW) with this fix, e.g. rtk-fixed (default: none)",
    )
    parser.add_argument(
        "--message-interval",
        choices=["supported", "unsupported", "silent"],
        default=defaults.message_interval,
        help="answer SET_MESSAGE_INTERVAL (default), refuse it as UNSUPPORTED, or ignore "
        "it, as old flight controllers do; REQUEST_DATA_STREAM always works",
    )
    parser.add_argument(
        "--frame",
        choices=["quad", "rover"],
        default=defaults.frame,
        help="a quadcopter (ArduCopter, or PX4 with --autopilot px4) or a wheeled rover "
        "(ArduRover); default quad",
    )
    parser.add_argument(
        "--autopilot",
        choices=["ardupilot", "px4"],
        default=defaults.autopilot,
        help="the autopilot the quad plays on the wire: its modes and answers (default ardupilot)",
    )
    parser.add_argument(
        "--lidar",
        type=_listen,
        default=None,
        metavar="tcp:HOST:PORT",
        help="fit a 2-D LIDAR and serve its serial bytes on this TCP address (default: no LIDAR)",
    )
    parser.add_argument(
        "--lidar-format",
        choices=LIDAR_FORMATS,
        default=defaults.lidar_format,
        help="the LIDAR's wire format (default ydlidar, a T-mini Pro): ydlidar-x4 for 2-byte "
        "samples with the intercept correction, ydlidar-g4 without, rplidar-* for a Slamtec "
        "sensor whose express scan sends that capsule, ld06 for LDROBOT (LD06/LD19/STL-27L)",
    )
    parser.add_argument(
        "--lidar-rate",
        type=float,
        default=defaults.lidar_rate_hz,
        metavar="HZ",
        help="the LIDAR's turns per second, 5..12 (default 10: 0.5 degree beams)",
    )
    parser.add_argument(
        "--scene",
        type=Path,
        default=None,
        metavar="FILE",
        help="a JSON scene of obstacles for the LIDAR (default: a small yard around home)",
    )
    parser.add_argument(
        "--camera",
        type=_listen,
        default=None,
        metavar="tcp:HOST:PORT",
        help="serve the camera's photos over HTTP here (GET /photos/{index}): the nadir view "
        "of a synthetic ground with ArUco targets from each shot's pose (default: "
        "CAMERA_FEEDBACK only, no images)",
    )
    parser.add_argument(
        "--camera-component",
        action="store_true",
        help="the camera is also a MAVLink camera component (component id 100, heartbeats of "
        "MAV_TYPE_CAMERA): at each shutter it sends CAMERA_IMAGE_CAPTURED with the photo "
        "server's address of the shot (needs --camera and --camera-model)",
    )
    parser.add_argument(
        "--camera-folder",
        type=Path,
        default=None,
        metavar="DIR",
        help="the camera writes each shot's rendered photo into DIR (DSC00001.JPG, ...), as a "
        "camera's SD card fills (needs --camera-model)",
    )
    parser.add_argument(
        "--camera-model",
        type=_camera_model,
        default=None,
        metavar="SW_MM,SH_MM,W_PX,H_PX,F_MM",
        help="the camera the component's and the folder's photos are rendered with: sensor "
        "width,height (mm), image width,height (px), focal length (mm)",
    )
    parser.add_argument(
        "--ground",
        type=_home,
        default=None,
        metavar="LAT,LON,ALT_MSL",
        help="the camera's synthetic ground: its origin and elevation (default: home); give "
        "a fleet's simulators the same one, so that their photos show the same ground",
    )
    parser.add_argument(
        "--param",
        type=_param,
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="set a parameter at boot, in the autopilot's own names and units, as SITL's "
        "--defaults does (repeatable), e.g. SYSID_MYGCS=254; a name the vehicle does not "
        "have or a value out of its range is refused (default: the autopilot's defaults)",
    )
    return parser


def _join_negative_values(argv: Sequence[str]) -> list[str]:
    """``--home -35.3,149.1,584`` as ``--home=-35.3,...``: argparse would take the value,
    starting with a dash, for an option."""
    joined: list[str] = []
    values = iter(argv)
    for arg in values:
        if arg in ("--home", "--ground"):
            value = next(values, None)
            joined.append(arg if value is None else f"{arg}={value}")
        else:
            joined.append(arg)
    return joined


def parse_args(argv: Sequence[str] | None = None) -> SimulatorConfig:
    """Settings from the command line; argparse exits (code 2) on a bad argument."""
    parser = build_parser()
    args = parser.parse_args(_join_negative_values(sys.argv[1:] if argv is None else argv))
    try:
        return SimulatorConfig(
            listen=args.listen,
            system_id=args.system_id,
            home=args.home,
            speedup=args.speedup,
            log_level=args.log_level,
            gps2_fix=None if args.gps2 is None else GPS2_FIX_TYPES[args.gps2],
            message_interval=args.message_interval,
            frame=args.frame,
            autopilot=args.autopilot,
            lidar=args.lidar,
            lidar_rate_hz=args.lidar_rate,
            lidar_format=args.lidar_format,
            scene=args.scene,
            camera=args.camera,
            camera_component=args.camera_component,
            camera_folder=args.camera_folder,
            camera_model=args.camera_model,
            ground=args.ground,
            params=tuple(args.param),
        )
    except ValueError as error:  # a combination the options cannot express
        parser.error(str(error))
