"""`gcs`: one entry point for the hub, the agent, the simulator and the demo.

Each subcommand imports its own part lazily, so `gcs agent` on a Raspberry Pi never
imports FastAPI or SQLAlchemy.
"""

from __future__ import annotations

import argparse
import logging
import os
import signal
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from common.log_escaping import escape_control_characters_in_logs
from gcs.demo_camera import DEMO_CAMERA_MODEL
from gcs.demo_lidars import DEFAULT_DEMO_LIDAR, DEMO_LIDAR_NAMES

if TYPE_CHECKING:
    from backend.settings import HubSettings
    from gcs.launcher import FleetPlan, LocalFleet

LOG_FORMAT = "%(asctime)s %(levelname)-7s %(name)s: %(message)s"  # as vehicle_agents.cli


def _configure_logging(level: str) -> None:
    logging.basicConfig(level=level.upper(), format=LOG_FORMAT)
    # A peer's text (a user name, a STATUSTEXT, the hub's error reply) never forges a line.
    escape_control_characters_in_logs()


# The extra each subcommand needs beyond the agent's base dependencies.
EXTRAS = {"hub": "hub", "demo": "hub", "sim": "simulator", "tiles": "hub"}


def _needs_extra(command: str, error: ModuleNotFoundError) -> int:
    """Say which extra to install when a subcommand's packages are not there."""
    extra = EXTRAS[command]
    print(
        f"gcs {command}: this install lacks {error.name!r}, which `gcs {command}` needs: "
        f"install the {extra!r} extra, e.g. pip install 'fleet-gcs[{extra}]' "
        f"(or pip install --require-hashes -r requirements/{extra}.txt from a checkout). "
        "An agent-only install runs only `gcs agent` / `gcs-agent`.",
        file=sys.stderr,
    )
    return 2


def _hub(args: argparse.Namespace) -> int:
    import uvicorn
    from pydantic import ValidationError

    from backend.app import create_app
    from backend.settings import HubSettings

    overrides: dict[str, Any] = {
        "host": args.host,
        "port": args.port,
        "data_dir": args.data_dir,
        "forwarded_allow_ips": args.forwarded_allow_ips,
    }
    try:
        settings = HubSettings(
            **{key: value for key, value in overrides.items() if value is not None}
        )
    except (ValidationError, ValueError, OSError) as error:
        # A configuration mistake or a refusal: say which, not a traceback.
        print(f"gcs hub: invalid settings: {error}", file=sys.stderr)
        return 2
    _warn_about_exposure(settings, tls=args.ssl_certfile is not None)
    # Everything the hub writes (database, uploaded .tlogs) is for its own user only.
    os.umask(0o077)
    settings.data_dir.mkdir(mode=0o700, parents=True, exist_ok=True)
    settings.data_dir.chmod(0o700)
    # The event loop shares the GIL with the hub's worker threads (survey plans, file
    # imports, password checks' bookkeeping, storage): at Python's default 5 ms a
    # CPU-bound thread held every request waiting behind it for that long, several times
    # over in one request. 1 ms hands the loop back its turn sooner.
    sys.setswitchinterval(0.001)
    uvicorn.run(
        create_app(settings),
        host=settings.host,
        port=settings.port,
        log_level=args.log_level.lower(),
        ws_max_size=settings.max_frame_bytes,
        # Bounds on what slow or idle clients can hold (a body timeout is in the app).
        limit_concurrency=settings.max_connections,
        timeout_keep_alive=settings.keep_alive_timeout_s,
        # uvicorn otherwise waits for every request in progress before it stops: a hub
        # told to stop kept planning a survey for as long as the plan took.
        timeout_graceful_shutdown=settings.shutdown_grace_s,
        ssl_certfile=args.ssl_certfile,
        ssl_keyfile=args.ssl_keyfile,
        # Client addresses (audit, login limits) come from X-Forwarded-For only when
        # the connection is from a trusted proxy.
        proxy_headers=True,
        forwarded_allow_ips=settings.forwarded_allow_ips,
    )
    return 0


def _warn_about_exposure(settings: HubSettings, tls: bool) -> None:
    """Say loudly, at start, what a hub reachable from the network lacks."""
    log = logging.getLogger("gcs.hub")
    if settings.on_loopback:
        return
    if settings.environment == "development":
        log.warning(
            "DEVELOPMENT MODE ON THE NETWORK (%s:%d): default passwords, short agent tokens "
            "and plain-HTTP cookies are accepted; anyone who reaches this port can log in "
            "and command the fleet. Only on a network you trust.",
            settings.host,
            settings.port,
        )
    if not tls:
        log.warning(
            "serving plain HTTP on %s:%d: passwords and tokens cross the network in clear "
            "unless a TLS proxy is in front (see deploy/nginx.conf)",
            settings.host,
            settings.port,
        )


def _agent(args: argparse.Namespace) -> int:
    from vehicle_agents.cli import run

    return run(args, prog="gcs agent")


def _sim(args: argparse.Namespace, rest: list[str]) -> int:
    from simulator import main as simulator_main

    return simulator_main(rest)


def demo_plan(args: argparse.Namespace) -> FleetPlan:
    """The fleet `gcs demo` starts from its options (secrets kept in the data folder)."""
    from gcs.launcher import FleetPlan

    return FleetPlan.reusing_secrets(
        args.data_dir,
        vehicles=args.vehicles,
        host=args.host,
        port=args.port,
        speedup=args.speedup,
        camera_model=None if args.no_cameras else args.camera_model,
        lidars=args.lidar is not None,
        lidar=args.lidar or DEFAULT_DEMO_LIDAR,
    )


def _demo(args: argparse.Namespace) -> int:
    from gcs.launcher import LocalFleet

    plan = demo_plan(args)
    fleet = LocalFleet(plan)
    log = logging.getLogger("gcs.demo")
    # Every way of asking the launcher to end stops the fleet the way Ctrl-C does: also
    # SIGINT where the shell started us with it ignored (`gcs demo &` in a script), and
    # SIGHUP (the terminal closed), unless ignored on purpose (nohup).
    stopping = [signal.SIGINT, signal.SIGTERM]
    if signal.getsignal(signal.SIGHUP) is not signal.SIG_IGN:
        stopping.append(signal.SIGHUP)
    for signum in stopping:
        signal.signal(signum, _interrupt)
    try:
        fleet.start()
        fleet.wait_until_ready()
        print(
            f"\nFleet GCS demo: {plan.vehicles} simulated vehicles (speed-up {plan.speedup:g}x)\n"
            f"  dashboard  {plan.public_http}/\n"
            f"  log in     admin / {plan.admin_password}\n"
            f"  API docs   {plan.public_http}/docs\n"
            f"  logs       {fleet.log_dir}/\n"
            f"{_simulator_ports(fleet)}"
            f"{_exposure_note(plan.host)}"
            "Press Ctrl-C to stop.\n",
            flush=True,
        )
        while True:
            fleet.check_alive()
            time.sleep(1.0)  # supervising: notice a child that died
    except KeyboardInterrupt:
        log.info("stopping")
    finally:
        # A second signal must not cut the orderly stop short (the stop is bounded).
        for signum in stopping:
            signal.signal(signum, signal.SIG_IGN)
        fleet.stop()
    return 0


def _simulator_ports(fleet: LocalFleet) -> str:
    """Each simulator's MAVLink address, for QGroundControl or MAVProxy beside the agent."""
    lines = "".join(
        f"    {fleet.vehicle_id(index):10} {fleet.sim_address(index)}\n"
        for index in sorted(fleet.sim_ports)
    )
    return f"  MAVLink    each simulator, for QGroundControl (TCP) or MAVProxy --master:\n{lines}"


def _exposure_note(host: str) -> str:
    """What the banner says when the demo is reachable from the network."""
    from common.addresses import is_loopback

    if is_loopback(host):
        return ""
    return (
        f"WARNING: listening on {host} with plain HTTP and development settings: anyone\n"
        "on this network who has the password can command the fleet, and can read it on\n"
        "the wire. Use it only on a field LAN you trust.\n"
    )


def _tiles(args: argparse.Namespace) -> int:
    from gcs.tiles import run

    return run(args)


def _interrupt(signum: int, frame: object) -> None:
    """A stopping signal stops the demo the way Ctrl-C does."""
    raise KeyboardInterrupt


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="gcs", description=__doc__)
    parser.add_argument("--log-level", default="INFO")
    commands = parser.add_subparsers(dest="command", required=True)

    hub = commands.add_parser("hub", help="run the hub (settings from GCS_* variables)")
    hub.add_argument("--host")
    hub.add_argument("--port", type=int)
    hub.add_argument("--data-dir", type=Path)
    hub.add_argument("--ssl-certfile", help="serve HTTPS/WSS directly with this certificate")
    hub.add_argument("--ssl-keyfile")
    hub.add_argument(
        "--forwarded-allow-ips", help="proxies trusted for X-Forwarded-For (127.0.0.1)"
    )

    try:
        from vehicle_agents.cli import add_agent_arguments
    except ModuleNotFoundError as error:
        # The hub's image holds no agent: there, `gcs agent` is not a command.
        if error.name != "vehicle_agents":
            raise
    else:
        agent = commands.add_parser("agent", help="bridge one flight controller to the hub")
        add_agent_arguments(agent)

    commands.add_parser(
        "sim", help="run a simulated MAVLink copter (see `gcs sim --help`)", add_help=False
    )

    from gcs.tiles import add_tiles_arguments

    tiles = commands.add_parser("tiles", help="the hub's offline base maps (.mbtiles, .pmtiles)")
    add_tiles_arguments(tiles)

    demo = commands.add_parser("demo", help="hub + simulated fleet + agents, one command")
    demo.add_argument("--vehicles", type=int, default=3)
    demo.add_argument(
        "--host",
        default="127.0.0.1",
        help="address to listen on (127.0.0.1); 0.0.0.0 lets a tablet on the LAN connect",
    )
    demo.add_argument("--port", type=int, default=8000)
    demo.add_argument("--data-dir", type=Path, default=Path("data"))
    demo.add_argument("--speedup", type=float, default=1.0)
    demo.add_argument(
        "--camera-model",
        type=_camera_model,
        default=DEMO_CAMERA_MODEL,
        metavar="SW_MM,SH_MM,W_PX,H_PX,F_MM",
        help="the camera every vehicle carries: sensor width,height (mm), image width,height "
        "(px), focal length (mm); its survey photos, rendered by the simulator, go to the "
        "hub, which offers it as a survey preset named after the vehicles (default: "
        f"{DEMO_CAMERA_MODEL}, 1.2 MP; 13.2,8.8,5472,3648,8.8 is a DJI Phantom 4 Pro's)",
    )
    demo.add_argument(
        "--no-cameras",
        action="store_true",
        help="fit no cameras (no survey photos, no mosaic)",
    )
    demo.add_argument(
        "--lidar",
        nargs="?",
        const=DEFAULT_DEMO_LIDAR,
        choices=DEMO_LIDAR_NAMES,
        metavar="FORMAT",
        help="fit every vehicle with a 2-D LIDAR whose scans show on the map and in 3D, "
        f"speaking this wire format (read by the agent's parser for it; {DEFAULT_DEMO_LIDAR} "
        f"when none is given): {', '.join(DEMO_LIDAR_NAMES)} (default: no LIDAR)",
    )
    return parser


def _camera_model(text: str) -> str:
    """An agent's --camera-model, checked here so that a typo stops the demo at once."""
    from protocol.photos import parse_camera_model

    try:
        parse_camera_model(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None
    return text


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args, rest = parser.parse_known_args(argv if argv is not None else sys.argv[1:])
    _configure_logging(args.log_level)
    if args.command != "sim" and rest:
        parser.error(f"unrecognized arguments: {' '.join(rest)}")
    handlers: dict[str, Callable[[argparse.Namespace], int]] = {
        "hub": _hub,
        "agent": _agent,
        "demo": _demo,
        "sim": lambda args: _sim(args, rest),
        "tiles": _tiles,
    }
    try:
        return handlers[args.command](args)
    except ModuleNotFoundError as error:
        if args.command not in EXTRAS or not _is_third_party(error):
            raise
        return _needs_extra(args.command, error)


def _is_third_party(error: ModuleNotFoundError) -> bool:
    """A dependency missing from the install, not a module of ours (that is a bug)."""
    ours = {"protocol", "common", "vehicle_agents", "simulator", "backend", "gcs"}
    return (error.name or "").partition(".")[0] not in ours
