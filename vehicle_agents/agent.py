"""The agent process: one flight controller, one hub, telemetry and commands between."""

from __future__ import annotations

import asyncio
import logging
import sqlite3
import uuid
from collections.abc import Awaitable, Callable

from protocol.messages import (
    PROTOCOL_VERSION,
    Command,
    CommandOutcome,
    Hello,
    ManualStartCommand,
    ManualStopCommand,
)
from protocol.photos import parse_camera_model
from vehicle_agents import __version__
from vehicle_agents.config import AgentSettings, default_vehicle_id, hub_http_base
from vehicle_agents.control.executor import CommandExecutor
from vehicle_agents.control.formation_runner import FormationRunner
from vehicle_agents.control.hub_failsafe import HubLinkFailsafe, reconnect_backoff
from vehicle_agents.control.manual import ManualPilot
from vehicle_agents.fcu.available_modes import AvailableModes
from vehicle_agents.fcu.events import FcuLinkEvents
from vehicle_agents.fcu.link import FcuLink
from vehicle_agents.fcu.param_metadata import ParamMetadata
from vehicle_agents.fcu.streams import StreamRequester
from vehicle_agents.forwarding.forwarder import MavlinkForwarder
from vehicle_agents.health import HealthFile
from vehicle_agents.hub.link import HubLink, HubTimeouts, ModeReport, VehicleIdInUse
from vehicle_agents.hub.outbox import Outbox, SpillFile
from vehicle_agents.publishing.events import EventSource
from vehicle_agents.publishing.telemetry import TelemetryPublisher, current_state
from vehicle_agents.sensors.fcu_time import FcuClock, PoseHistory, ask_timesync
from vehicle_agents.sensors.mavlink_ranges import MavlinkRangeSource
from vehicle_agents.sensors.paced_clock import PacedClock
from vehicle_agents.sensors.relay import DiskBacklog, ScanOutbox, ScanRelay, parse_mount
from vehicle_agents.sensors.ros2 import SCHEME as ROS2_SCHEME
from vehicle_agents.sensors.ros2 import LaserScanSource
from vehicle_agents.sensors.serial_lidar import SerialLidarSource
from vehicle_agents.sensors.turn import ScanSource
from vehicle_agents.tlog.pruning import MIB, TlogRetention
from vehicle_agents.tlog.recorder import TlogRecorder
from vehicle_agents.tlog.uploads import TlogUploader

log = logging.getLogger(__name__)

CAPABILITIES = ["telemetry", "commands", "events", "manual", "formation"]
SCAN_CAPABILITY = "scans"


async def run_agent(settings: AgentSettings) -> None:
    """Runs until cancelled; raises VehicleIdInUse (on its own, not in a group) when the
    hub keeps another agent with this vehicle id, which no retry would change."""
    try:
        await _run(settings)
    except* VehicleIdInUse as refused:
        raise refused.exceptions[0] from None


async def _run(settings: AgentSettings) -> None:
    token = settings.token_value()  # refused before anything starts
    link = FcuLink(settings.fcu, source_system=settings.source_system)
    streams = StreamRequester(link, settings.stream_rates_hz)  # checks the rates first
    async with asyncio.TaskGroup() as tasks:
        tasks.create_task(link.run())
        if settings.mavlink_forward:  # third-party GCSs, from the start, whatever the hub does
            # One set of rates for the agent and the GCSs: the forward merges theirs in.
            forward = MavlinkForwarder(link, settings.mavlink_forward, streams.merger)
            tasks.create_task(forward.run())
        tasks.create_task(streams.run())  # on every link up
        log.info("waiting for a heartbeat from %s", settings.fcu)
        await link.wait_identified()
        assert link.modes is not None
        assert link.target_system is not None
        vehicle_id = settings.vehicle_id or default_vehicle_id(link.modes.vehicle_type)
        hello = Hello(
            protocol=PROTOCOL_VERSION,
            vehicle_id=vehicle_id,
            autopilot=link.modes.autopilot,
            vehicle_type=link.modes.vehicle_type,
            system_id=link.target_system,
            modes=link.modes.names,
            capabilities=CAPABILITIES + ([SCAN_CAPABILITY] if settings.lidar else []),
            agent_version=__version__,
            stream_id=uuid.uuid4().hex[:16],
            # The hub offers this camera as a survey preset and checks surveys against it.
            camera=parse_camera_model(settings.camera_model) if settings.camera else None,
        )
        # The autopilot's own mode list, once read, replaces the fixed table the hello has.
        mode_report = ModeReport(hello.modes)
        tasks.create_task(AvailableModes(link, lambda table: mode_report.update(table.names)).run())
        outbox = open_outbox(settings, vehicle_id, hello.stream_id)
        events = EventSource(
            outbox, link.modes.autopilot, has_image_source=settings.camera is not None
        )
        link.listeners.append(events.on_message)
        link.state_listeners.append(FcuLinkEvents(events.emit).on_link_change)
        executor = CommandExecutor(link)
        if link.modes.autopilot == "px4":  # the autopilot that publishes its metadata
            executor.params.metadata = ParamMetadata(link)
            tasks.create_task(executor.params.metadata.run())
        # The autopilot's pace, for everything that waits on the aircraft's behalf (the
        # deadman, the formation follower, the hub-link failsafe and its reconnects).
        paced = PacedClock()
        link.listeners.append(paced.on_message)
        pilot = ManualPilot(
            link, executor, events.emit, clock=paced, source_system=settings.source_system
        )
        tasks.create_task(pilot.run())
        formation = FormationRunner(link, executor, events.emit, clock=paced)
        tasks.create_task(formation.run())
        scans = None
        scan_stats = None
        if settings.lidar:
            relay = scan_relay(settings, link, vehicle_id)
            scans = relay.outbox
            scan_stats = relay.source_stats
            tasks.create_task(relay.run())
            tasks.create_task(ask_timesync(link.send))
        hub = HubLink(
            settings.hub,
            token,
            hello,
            outbox,
            manual_commands(pilot, executor.execute),
            live_state=lambda: current_state(link, outbox),
            on_manual=pilot.on_frame,
            on_formation=formation.on_hub,
            scans=scans,
            scan_stats=scan_stats,
            fallback_urls=settings.hub_fallback,
            modes=mode_report,
            timeouts=HubTimeouts(
                reconnect=reconnect_backoff(
                    settings.hub_failsafe_action,
                    settings.hub_failsafe_timeout_s,
                    HubTimeouts().reconnect,
                )
            ),
            reconnect_sleep=paced.sleep,
        )
        tasks.create_task(TelemetryPublisher(link, outbox).run(settings.telemetry_rate_hz))
        tasks.create_task(hub.run())
        failsafe = HubLinkFailsafe(
            hub.connected,
            hub.disconnected,
            executor,
            link,
            events.emit,
            settings.hub_failsafe_action,
            settings.hub_failsafe_timeout_s,
            paced,
        )
        tasks.create_task(failsafe.run())
        if settings.health_file is not None:
            health = HealthFile(settings.health_file, lambda: link.connected, hub.connected.is_set)
            tasks.create_task(health.run())
        if settings.camera is not None:
            from vehicle_agents.camera.wiring import start_camera  # only with a camera

            start_camera(settings, link, vehicle_id, token, events.emit, tasks)
        if settings.tlog_dir is not None:
            recorder = TlogRecorder(settings.tlog_dir, vehicle_id)
            link.recorder = recorder.record
            url = f"{hub_http_base(settings.hub)}/api/v1/vehicles/{vehicle_id}/tlogs"
            uploader = TlogUploader(
                recorder,
                url,
                token,
                notify=lambda text, severity: events.emit("upload", text, severity),
                retention=TlogRetention(
                    keep_days=settings.tlog_keep_days,
                    keep_bytes=round(settings.tlog_keep_mb * MIB),
                ),
            )
            link.listeners.append(uploader.on_message)
            tasks.create_task(uploader.run())


def manual_commands(
    pilot: ManualPilot, execute: Callable[[Command], Awaitable[CommandOutcome]]
) -> Callable[[Command], Awaitable[CommandOutcome]]:
    """The lease's start and end go to the manual pilot, every other command to the FCU."""

    async def run(command: Command) -> CommandOutcome:
        if isinstance(command, ManualStartCommand):
            return await pilot.start()
        if isinstance(command, ManualStopCommand):
            return await pilot.stop()
        return await execute(command)

    return run


def scan_relay(settings: AgentSettings, link: FcuLink, vehicle_id: str) -> ScanRelay:
    """The LIDAR's turns, stamped with the flight controller's clock and pose."""
    assert settings.lidar is not None
    poses = PoseHistory(FcuClock())
    link.listeners.append(poses.on_message)
    source: ScanSource
    name = settings.lidar_model
    if settings.lidar == "mavlink":
        name = "mavlink"
        ranges = MavlinkRangeSource()
        link.listeners.append(ranges.on_message)
        source = ranges
    elif settings.lidar.startswith(ROS2_SCHEME):
        source = LaserScanSource(settings.lidar)
        name = "ros2"
    else:
        source = SerialLidarSource(
            settings.lidar,
            settings.lidar_resolution_deg,
            settings.lidar_baud,
            settings.lidar_model,
            settings.lidar_scan_mode,
        )
    backlog = None
    if settings.outbox_dir is not None:
        path = settings.outbox_dir / f"{vehicle_id}.scans.sqlite"
        try:
            backlog = DiskBacklog(path)
        except (OSError, sqlite3.Error) as error:
            log.error("scan backlog file %s unusable (%s); keeping it in memory", path, error)
    outbox = ScanOutbox(settings.scan_budget, backlog)
    return ScanRelay(source, poses, outbox, parse_mount(settings.lidar_mount), source_name=name)


def open_outbox(settings: AgentSettings, vehicle_id: str, stream_id: str) -> Outbox:
    """The outbox, spilling to disk when the agent has a directory for it."""
    spill = None
    if settings.outbox_dir is not None:
        path = settings.outbox_dir / f"{vehicle_id}.outbox.sqlite"
        try:
            spill = SpillFile(path)
        except (OSError, sqlite3.Error) as error:
            # Better a memory-only outbox than no agent: the vehicle still needs its link.
            log.error("outbox file %s unusable (%s); keeping the outbox in memory", path, error)
    return Outbox(stream_id, settings.outbox_limit, spill)
