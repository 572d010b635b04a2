"""The agent process: one flight controller, one hub, telemetry and commands between."""

from __future__ import annotations

import asyncio
import logging
import sqlite3
import time
import uuid
from collections.abc import Awaitable, Callable

from protocol.messages import (
    PROTOCOL_VERSION,
    Command,
    CommandOutcome,
    Event,
    EventKind,
    Hello,
    ManualStartCommand,
    ManualStopCommand,
    Photo,
    Telemetry,
    VehicleState,
    encode,
)
from vehicle_agents import __version__
from vehicle_agents.config import AgentSettings, default_vehicle_id, hub_http_base
from vehicle_agents.control.executor import CommandExecutor
from vehicle_agents.control.formation_runner import FormationRunner
from vehicle_agents.control.hub_failsafe import HubLinkFailsafe, reconnect_backoff
from vehicle_agents.control.manual import ManualPilot
from vehicle_agents.fcu.available_modes import AvailableModes
from vehicle_agents.fcu.events import FcuLinkEvents
from vehicle_agents.fcu.link import FcuLink
from vehicle_agents.fcu.messages import MavMessage
from vehicle_agents.fcu.missions import mission_number
from vehicle_agents.fcu.modes import is_armed
from vehicle_agents.fcu.param_metadata import ParamMetadata
from vehicle_agents.fcu.streams import StreamRequester
from vehicle_agents.forwarding.forwarder import MavlinkForwarder
from vehicle_agents.health import HealthFile
from vehicle_agents.hub.link import HubLink, HubTimeouts, ModeReport, VehicleIdInUse
from vehicle_agents.hub.outbox import Outbox, SpillFile
from vehicle_agents.sensors.fcu_time import FcuClock, PoseHistory, ask_timesync
from vehicle_agents.sensors.paced_clock import PacedClock
from vehicle_agents.sensors.relay import DiskBacklog, ScanOutbox, ScanRelay, parse_mount
from vehicle_agents.sensors.ros2 import SCHEME as ROS2_SCHEME
from vehicle_agents.sensors.ros2 import LaserScanSource
from vehicle_agents.sensors.sources import MavlinkRangeSource, ScanSource, SerialLidarSource
from vehicle_agents.telemetry.mission_progress import ReachedItems
from vehicle_agents.telemetry.shutters import ShutterMatcher, captured_alt_rel, from_autopilot
from vehicle_agents.telemetry.snapshot import link_snapshot
from vehicle_agents.telemetry.statustext import StatusTextJoiner
from vehicle_agents.tlog.pruning import MIB, TlogRetention
from vehicle_agents.tlog.recorder import TlogRecorder
from vehicle_agents.tlog.uploads import TlogUploader

log = logging.getLogger(__name__)
SEVERITY_NOTICE = 5  # MAV_SEVERITY_NOTICE: normal but significant

# CAMERA_FEEDBACK.flags: a photo (CAMERA_FEEDBACK_FLAGS; not a video or a bad capture).
CAMERA_FEEDBACK_PHOTO = 0
CAPTURE_FAILED = 0  # CAMERA_IMAGE_CAPTURED.capture_result: 1 success, 0 failure

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


def current_state(link: FcuLink, outbox: Outbox) -> VehicleState:
    """The vehicle now, with the agent's own delivery counters."""
    return link_snapshot(link).model_copy(
        update={"outbox_pending": len(outbox), "outbox_dropped": outbox.dropped}
    )


class TelemetryPublisher:
    """Snapshots of the vehicle into the outbox, numbered: at a fixed rate, and at once
    when a HEARTBEAT says the motors armed or disarmed. The hub's flight log finds
    flights from arm to disarm in these snapshots; an arming shorter than the period (a
    take-off landed straight away, an arm and a disarm) would otherwise fall between two
    of them and leave no flight at all."""

    def __init__(self, link: FcuLink, outbox: Outbox) -> None:
        self._link = link
        self._outbox = outbox
        self._seq = 0
        self._armed: bool | None = None  # as the last snapshot said
        # Listeners run as each message is handled, before the next one of the batch:
        # the snapshot taken here still holds the heartbeat that changed.
        link.listeners.append(self._on_message)

    def publish(self) -> None:
        state = current_state(self._link, self._outbox)
        body = encode(Telemetry(seq=self._seq, time=time.time(), state=state))
        self._outbox.put("telemetry", self._seq, body)
        self._seq += 1
        self._armed = state.armed

    def _on_message(self, message: MavMessage) -> None:
        if (
            message.get_type() == "HEARTBEAT"
            and message.get_srcComponent() == self._link.target_component  # the autopilot's
            and is_armed(message) != self._armed
        ):
            self.publish()

    async def run(self, rate_hz: float) -> None:
        period = 1.0 / rate_hz
        next_at = time.monotonic()
        while True:
            self.publish()
            next_at += period
            await asyncio.sleep(max(0.0, next_at - time.monotonic()))


class EventSource:
    """STATUSTEXTs and mission progress become numbered events for the hub's flight log:
    long texts joined from their chunks, each reached item once per pass."""

    def __init__(
        self,
        outbox: Outbox,
        autopilot: str,
        clock: Callable[[], float] = time.monotonic,
        *,
        has_image_source: bool = True,
    ) -> None:
        self._outbox = outbox
        # Without a camera source (--camera) a shutter is counted but has no image: SITL's
        # camera feedback, or a drone whose camera nobody told the agent of. Said once.
        self._has_image_source = has_image_source
        self._told_no_image = False
        self._autopilot = autopilot
        self._seq = 0
        self._clock = clock
        self._texts = StatusTextJoiner()
        self._reached = ReachedItems()
        # The latest GLOBAL_POSITION_INT (lat, lon, metres above home): where PX4's
        # CAMERA_TRIGGER, which carries no position, was taken.
        self._position: tuple[float, float, float] | None = None
        self._shutters = ShutterMatcher()  # PX4 tells of a shutter twice
        self._home_msl: float | None = None  # for CAMERA_IMAGE_CAPTURED's height

    def on_message(self, message: MavMessage) -> None:
        kind = message.get_type()
        now = self._clock()
        # An unfinished chunked text is let out on the next message after its wait
        # (heartbeats come every second), so no timer of its own is needed.
        texts = self._texts.add(message, now) if kind == "STATUSTEXT" else self._texts.due(now)
        for text in texts:
            self.emit("statustext", text.text, text.severity)
        if kind == "MISSION_CURRENT":
            self._reached.current(int(message.seq))
        elif kind == "MISSION_ITEM_REACHED" and self._reached.reached(int(message.seq)):
            number = mission_number(int(message.seq), self._autopilot)
            self.emit("mission", f"reached mission item {number}", None, mission_item=number)
        elif kind == "GLOBAL_POSITION_INT" and (message.lat or message.lon):
            self._position = (message.lat / 1e7, message.lon / 1e7, message.relative_alt / 1000.0)
            self._home_msl = message.alt / 1000.0 - message.relative_alt / 1000.0
        elif kind == "CAMERA_FEEDBACK" and int(message.flags) == CAMERA_FEEDBACK_PHOTO:
            # ArduPilot sends one per shutter release (AP_Camera), to every GCS link: the
            # photo's place for the survey's progress and the flight log.
            self._photo(
                Photo(
                    index=int(message.img_idx),
                    lat=message.lat / 1e7,
                    lon=message.lng / 1e7,
                    alt_rel=float(message.alt_rel),
                )
            )
        elif (
            kind == "CAMERA_IMAGE_CAPTURED"
            and from_autopilot(message)
            and int(message.capture_result) != CAPTURE_FAILED
        ):
            # PX4's camera_feedback sends one per shutter release, to every GCS link, with
            # where it was; its CAMERA_TRIGGER (the same index) may have come first.
            index = int(message.image_index)
            if (message.lat or message.lon) and self._shutters.is_new(kind, index, now):
                self._photo(
                    Photo(
                        index=index,
                        lat=message.lat / 1e7,
                        lon=message.lon / 1e7,
                        alt_rel=captured_alt_rel(message, self._home_msl),
                    )
                )
        elif kind == "CAMERA_TRIGGER" and self._position is not None:
            # PX4's camera_trigger sends one per shutter release (where the agent asks for
            # it), without a position: the latest one the autopilot streamed (a tenth of
            # a second old at 10 Hz).
            index = int(message.seq)
            if self._shutters.is_new(kind, index, now):
                lat, lon, alt_rel = self._position
                self._photo(Photo(index=index, lat=lat, lon=lon, alt_rel=alt_rel))

    def _photo(self, photo: Photo) -> None:
        self.emit(
            "camera",
            f"photo {photo.index} at {photo.lat:.7f}, {photo.lon:.7f}, "
            f"{photo.alt_rel:.1f} m above home",
            None,
            photo=photo,
        )
        if not self._has_image_source and not self._told_no_image:
            self._told_no_image = True
            text = (
                f"photo {photo.index}: the autopilot's camera fired, but no image source is "
                "configured (--camera): shots are counted, no image is uploaded"
            )
            log.warning("%s", text)
            self.emit("upload", text, SEVERITY_NOTICE)

    def emit(
        self,
        kind: EventKind,
        text: str,
        severity: int | None,
        *,
        mission_item: int | None = None,
        photo: Photo | None = None,
    ) -> None:
        event = Event(
            seq=self._seq,
            time=time.time(),
            kind=kind,
            severity=severity,
            text=text,
            mission_item=mission_item,
            photo=photo,
        )
        self._outbox.put("event", self._seq, encode(event))
        self._seq += 1
