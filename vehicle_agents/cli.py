"""The agent's command line: `gcs-agent` (the agent-only install) and `gcs agent`.

Every setting has one name, the field of `AgentSettings`: the config-file key
(``telemetry_rate_hz``), the flag (``--telemetry-rate-hz``) and the environment variable
(``GCS_AGENT_TELEMETRY_RATE_HZ``) are all derived from it, so they cannot drift apart.
"""

from __future__ import annotations

import argparse
import asyncio
import logging
import os
import signal
import sys
from collections.abc import Coroutine
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from common.log_escaping import escape_control_characters_in_logs
from common.retry import stop_retrying_when
from vehicle_agents.config import (
    ENV_PREFIX,
    AgentSettings,
    SettingsError,
    describe_errors,
    flag_for,
    load_agent_settings,
    ways_to_give,
)

LOG_FORMAT = "%(asctime)s %(levelname)-7s %(name)s: %(message)s"
# How long --print-id waits for the flight controller's heartbeat, which names its type.
PRINT_ID_TIMEOUT_S = 30.0
# sysexits' EX_CONFIG: a configuration error that restarting will not fix (gcs-agent.service
# does not restart on it). The agent exits with it when its vehicle id is another's.
EXIT_VEHICLE_ID_IN_USE = 78

# The flag of each setting: argparse's type and how it is given. Its name is the field's.
_FLAG_KINDS: dict[str, dict[str, Any]] = {
    "fcu": {"metavar": "URL"},
    "hub": {"metavar": "URL"},
    "hub_fallback": {"action": "append", "metavar": "URL"},
    "token": {"metavar": "TOKEN"},
    "vehicle_id": {"metavar": "ID"},
    "telemetry_rate_hz": {"type": float, "metavar": "HZ"},
    "source_system": {"type": int, "metavar": "SYSID"},
    "tlog_dir": {"type": Path, "metavar": "DIR"},
    "tlog_keep_days": {"type": float, "metavar": "DAYS"},
    "tlog_keep_mb": {"type": float, "metavar": "MIB"},
    "outbox_limit": {"type": int, "metavar": "FRAMES"},
    "outbox_dir": {"type": Path, "metavar": "DIR"},
    "health_file": {"type": Path, "metavar": "FILE"},
    "hub_failsafe_action": {"choices": ["continue", "hold", "rtl"]},
    "hub_failsafe_timeout_s": {"type": float, "metavar": "SECONDS"},
    "mavlink_forward": {"action": "append", "metavar": "ENDPOINT"},
    "stream_rates_hz": {"action": "append", "metavar": "MESSAGE=HZ"},
    "lidar": {"metavar": "DEVICE|tcp://HOST:PORT|mavlink"},
    "lidar_model": {"metavar": "MODEL"},
    "lidar_baud": {"type": int, "metavar": "BAUD"},
    "lidar_scan_mode": {"type": int, "metavar": "MODE"},
    "lidar_resolution_deg": {"type": float, "metavar": "DEG"},
    "lidar_mount": {"metavar": "F,R,D,ROLL,PITCH,YAW"},
    "scan_budget": {"type": int, "metavar": "SCANS"},
    "camera": {"metavar": "sim+http://HOST:PORT|opencv:DEVICE"},
    "camera_model": {"metavar": "SW_MM,SH_MM,W_PX,H_PX,F_MM"},
    "photo_dir": {"type": Path, "metavar": "DIR"},
    "photo_budget_mb": {"type": float, "metavar": "MIB"},
    "photo_upload_rate_mb": {"type": float, "metavar": "MIB_PER_S"},
    "photo_upload_concurrency": {"type": int, "metavar": "N"},
}
# Flags of earlier releases, still accepted (hidden) so existing units and scripts run.
_OLD_FLAGS = {
    "--telemetry-rate": "telemetry_rate_hz",
    "--hub-failsafe": "hub_failsafe_action",
    "--hub-failsafe-timeout": "hub_failsafe_timeout_s",
}


def add_agent_arguments(parser: argparse.ArgumentParser) -> None:
    """The agent's flags, one per setting, on ``parser`` (shared by `gcs agent`)."""
    parser.add_argument(
        "--config",
        type=Path,
        help="TOML settings file, keys as the flags below without '--' and with '_' "
        "(default /etc/gcs/agent.toml if present)",
    )
    parser.add_argument(
        "--print-id",
        action="store_true",
        help="print this vehicle's id (what an admin enrols) and exit; without --vehicle-id "
        "it waits for the flight controller's heartbeat, which names the vehicle type",
    )
    parser.add_argument(
        "--health",
        action="store_true",
        help="exit 0 if the running agent's health file (--health-file) is fresh and says "
        "both links are up, else say what is wrong and exit 1 (a container's health check)",
    )
    for name, field in AgentSettings.model_fields.items():
        default = (
            "required"
            if field.is_required()
            else _shown(field.get_default(call_default_factory=True))
        )
        parser.add_argument(
            flag_for(name),
            dest=name,
            help=f"{field.description or ''} ({ENV_PREFIX}{name.upper()}; {default})",
            **_FLAG_KINDS[name],
        )
    for flag, name in _OLD_FLAGS.items():
        parser.add_argument(flag, dest=name, help=argparse.SUPPRESS, **_FLAG_KINDS[name])


def _shown(default: Any) -> str:
    if default is None:
        return "unset"
    if default in ([], {}):
        return "none"
    return f"default {default}"


def overrides_from(args: argparse.Namespace) -> dict[str, Any]:
    """The settings given as flags (None where a flag was not given)."""
    given = {name: getattr(args, name) for name in AgentSettings.model_fields}
    rates = given["stream_rates_hz"]
    if rates is not None:
        given["stream_rates_hz"] = dict(_rate(text) for text in rates)
    return given


def _rate(text: str) -> tuple[str, str]:
    name, sep, value = text.partition("=")
    if not sep:
        raise SettingsError(f"--stream-rates-hz takes MESSAGE=HZ, e.g. ATTITUDE=20: {text!r}")
    return name.strip(), value.strip()


def run(args: argparse.Namespace, prog: str = "gcs-agent") -> int:
    """Run the agent (or print its id) with the parsed flags; the exit code."""
    try:
        settings = load_agent_settings(
            overrides_from(args), args.config, require_token=not (args.print_id or args.health)
        )
    except ValidationError as error:
        print(f"{prog}: invalid settings:\n{describe_errors(error)}", file=sys.stderr)
        return 2
    except (SettingsError, ValueError, OSError) as error:
        # A configuration mistake: say which setting, not a traceback.
        print(f"{prog}: invalid settings: {error}", file=sys.stderr)
        return 2
    if args.print_id:
        return print_id(settings, prog)
    if args.health:
        return report_health(settings, prog)
    from vehicle_agents.agent import run_agent
    from vehicle_agents.hub.link import VehicleIdInUse

    # What the agent writes (the outbox's telemetry, onboard .tlogs) is for its own user
    # only, on a companion computer that others may log in to.
    os.umask(0o077)

    try:
        return run_until_signalled(run_agent(settings), give_up=(VehicleIdInUse,))
    except VehicleIdInUse as refused:
        logging.getLogger("gcs.agent").error("stopping: %s", refused)
        return EXIT_VEHICLE_ID_IN_USE


def print_id(settings: AgentSettings, prog: str) -> int:
    """Print the vehicle id the agent will use; 1 if the flight controller never answered."""
    if settings.vehicle_id is not None:
        print(settings.vehicle_id)
        return 0
    from vehicle_agents.hub.identity import identify

    try:
        vehicle_id = asyncio.run(identify(settings, PRINT_ID_TIMEOUT_S))
    except TimeoutError:
        from vehicle_agents.config import default_vehicle_id

        print(
            f"{prog}: no heartbeat from {settings.fcu} within {PRINT_ID_TIMEOUT_S:g} s, and "
            "the default id starts with the vehicle type it names; it will be "
            f"{default_vehicle_id('<type>')} (<type>: multirotor, rover, fixed_wing, ...). "
            "Check --fcu, or choose an id with --vehicle-id.",
            file=sys.stderr,
        )
        return 1
    print(vehicle_id)
    return 0


def report_health(settings: AgentSettings, prog: str) -> int:
    """0 if the running agent says, in its fresh health file, that both links are up."""
    from vehicle_agents.health import check

    if settings.health_file is None:
        print(
            f"{prog}: --health reads the running agent's health file: give it as "
            + ways_to_give("health_file"),
            file=sys.stderr,
        )
        return 2
    problem = check(settings.health_file)
    if problem is not None:
        print(f"{prog}: unhealthy: {problem}", file=sys.stderr)
        return 1
    print("healthy: the flight controller and the hub are linked")
    return 0


def run_until_signalled(
    main: Coroutine[Any, Any, None],
    name: str = "agent",
    give_up: tuple[type[Exception], ...] = (),
) -> int:
    """Run a coroutine until it ends or SIGINT/SIGTERM cancels it; exit code 0 on a signal,
    1 on an error, and the exceptions in ``give_up`` raised for the caller to answer. Either
    way the log's last line says that ``name`` stopped, and why: an onboard computer's
    journal otherwise shows a process that just went quiet."""
    log = logging.getLogger(f"gcs.{name}")
    signals: list[str] = []

    async def runner() -> None:
        task = asyncio.current_task()
        assert task is not None
        loop = asyncio.get_running_loop()
        stopping = asyncio.Event()
        stop_retrying_when(stopping)  # before main starts its tasks, so they all see it

        def stop(signum: signal.Signals) -> None:
            signals.append(signum.name)
            log.info("%s: %s received, stopping", name, signum.name)
            stopping.set()
            task.cancel()

        for signum in (signal.SIGINT, signal.SIGTERM):
            loop.add_signal_handler(signum, stop, signum)
        await main

    try:
        asyncio.run(runner())
    except asyncio.CancelledError:
        log.info("%s stopped: %s", name, f"on {signals[0]}" if signals else "cancelled")
        return 0
    except give_up:
        raise
    except Exception as error:
        log.critical("%s stopped: %s: %s", name, type(error).__name__, error, exc_info=True)
        return 1
    log.info("%s stopped: its work ended", name)
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="gcs-agent",
        description="Bridge one flight controller (MAVLink) to the hub. "
        "`gcs-agent lidar-probe DEVICE` finds the LIDAR on a serial port instead.",
    )
    parser.add_argument("--log-level", default="INFO")
    add_agent_arguments(parser)
    return parser


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["lidar-probe"]:
        from vehicle_agents.sensors.lidar.probe import main as probe_main

        return probe_main(argv[1:])
    args = build_parser().parse_args(argv)
    logging.basicConfig(level=args.log_level.upper(), format=LOG_FORMAT)
    escape_control_characters_in_logs()
    return run(args)
