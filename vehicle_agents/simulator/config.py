"""Command-line settings of the simulator."""

from __future__ import annotations

import argparse
import logging
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

from vehicle_agents.simulator.clock import MAX_SPEEDUP
from vehicle_agents.simulator.geo import GeoPoint

# ArduPilot's SITL home, CMAC (Canberra Model Aircraft Club).
DEFAULT_HOME = GeoPoint(-35.363262, 149.165237, 584.0)

Scheme = Literal["tcp", "udp"]


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

    def __post_init__(self) -> None:
        if not 1 <= self.system_id <= 255:
            raise ValueError(f"system id must be 1..255, got {self.system_id}")
        if not 0.0 < self.speedup <= MAX_SPEEDUP:
            raise ValueError(f"speed-up must be > 0 and <= {MAX_SPEEDUP:g}, got {self.speedup}")


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
        return GeoPoint(lat, lon, alt)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected LAT,LON,ALT_MSL in degrees and metres, got {text!r}"
        ) from None


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
    return parser


def _join_negative_values(argv: Sequence[str]) -> list[str]:
    """``--home -35.3,149.1,584`` as ``--home=-35.3,...``: argparse would take the value,
    starting with a dash, for an option."""
    joined: list[str] = []
    values = iter(argv)
    for arg in values:
        if arg == "--home":
            value = next(values, None)
            joined.append(arg if value is None else f"{arg}={value}")
        else:
            joined.append(arg)
    return joined


def parse_args(argv: Sequence[str] | None = None) -> SimulatorConfig:
    """Settings from the command line; argparse exits (code 2) on a bad argument."""
    args = build_parser().parse_args(_join_negative_values(sys.argv[1:] if argv is None else argv))
    return SimulatorConfig(
        listen=args.listen,
        system_id=args.system_id,
        home=args.home,
        speedup=args.speedup,
        log_level=args.log_level,
    )
