"""Telemetry shaping: ask the flight controller for the messages the agent uses, at the
rates it uses them, each time the link comes up.

MAV_CMD_SET_MESSAGE_INTERVAL sets one message's rate and is acknowledged. Flight
controllers that answer it UNSUPPORTED, or not at all (old ArduPilot, some radios that
drop COMMAND_LONG), get the older REQUEST_DATA_STREAM instead: one rate per group of
messages (ArduPilot's SRx_ parameters), with no acknowledgement.

Another GCS on the same link can change those rates at any time; `RateWatch`
(stream_watch.py) measures what arrives, and the requester asks again for any message
that falls below its rate, the same way it asked the first time.
"""

from __future__ import annotations

import asyncio
import logging
import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Literal

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from vehicle_agents.fcu_link import FcuLink, LinkChange, MavMessage
from vehicle_agents.stream_watch import RateWatch, RateWatchSettings

log = logging.getLogger(__name__)

# What the agent's snapshot reads (HEARTBEAT comes at 1 Hz without asking), in the order
# they are requested: the first one also probes for SET_MESSAGE_INTERVAL support.
DEFAULT_RATES_HZ: Mapping[str, float] = {
    "GLOBAL_POSITION_INT": 10.0,
    "ATTITUDE": 10.0,
    "VFR_HUD": 4.0,
    "SYS_STATUS": 2.0,
    "GPS_RAW_INT": 2.0,
    "GPS2_RAW": 2.0,
    "BATTERY_STATUS": 1.0,
    "MISSION_CURRENT": 1.0,
    "EXTENDED_SYS_STATE": 1.0,
    "EKF_STATUS_REPORT": 1.0,  # ready to fly: the EKF uses the GPS (ArduPilot)
    "HOME_POSITION": 0.2,
}

# Messages PX4 sends on an event, not a clock, that its normal GCS link leaves out
# (mavlink_main.cpp streams CAMERA_TRIGGER only to onboard links): asked for with
# SET_MESSAGE_INTERVAL, at a rate no trigger sequence reaches, so each shutter's is sent
# (a slower rate would hold back one of two triggers a millisecond apart). Not watched:
# silence is no fault.
PX4_EVENT_RATES_HZ: Mapping[str, float] = {"CAMERA_TRIGGER": 100.0}

# REQUEST_DATA_STREAM's groups, as ArduPilot fills them (GCS_Common.cpp, the
# STREAM_*_msgs tables; ArduCopter 4.x). Messages in no group (HOME_POSITION,
# EXTENDED_SYS_STATE) can only be had through SET_MESSAGE_INTERVAL or on request.
DATA_STREAM_GROUPS: Mapping[int, tuple[str, ...]] = {
    mavlink2.MAV_DATA_STREAM_RAW_SENSORS: (
        "RAW_IMU",
        "SCALED_IMU2",
        "SCALED_IMU3",
        "SCALED_PRESSURE",
        "SCALED_PRESSURE2",
        "SCALED_PRESSURE3",
    ),
    mavlink2.MAV_DATA_STREAM_EXTENDED_STATUS: (
        "SYS_STATUS",
        "POWER_STATUS",
        "MEMINFO",
        "MISSION_CURRENT",
        "GPS_RAW_INT",
        "GPS_RTK",
        "GPS2_RAW",
        "GPS2_RTK",
        "NAV_CONTROLLER_OUTPUT",
        "FENCE_STATUS",
        "POSITION_TARGET_GLOBAL_INT",
    ),
    mavlink2.MAV_DATA_STREAM_POSITION: ("GLOBAL_POSITION_INT", "LOCAL_POSITION_NED"),
    mavlink2.MAV_DATA_STREAM_RC_CHANNELS: ("SERVO_OUTPUT_RAW", "RC_CHANNELS", "RC_CHANNELS_RAW"),
    mavlink2.MAV_DATA_STREAM_EXTRA1: ("ATTITUDE", "SIMSTATE", "AHRS2", "PID_TUNING"),
    mavlink2.MAV_DATA_STREAM_EXTRA2: ("VFR_HUD",),
    mavlink2.MAV_DATA_STREAM_EXTRA3: (
        "AHRS",
        "WIND",
        "RANGEFINDER",
        "DISTANCE_SENSOR",
        "SYSTEM_TIME",
        "BATTERY_STATUS",
        "EKF_STATUS_REPORT",
        "VIBRATION",
    ),
}
_GROUP_OF = {name: group for group, names in DATA_STREAM_GROUPS.items() for name in names}

INTERVAL_DEFAULT_US = 0  # SET_MESSAGE_INTERVAL param2: the flight controller's default rate
INTERVAL_DISABLED_US = -1  # ... and: stop sending
MAX_DATA_STREAM_HZ = 65535  # REQUEST_DATA_STREAM.req_message_rate is a uint16

Method = Literal["message_interval", "data_stream"]


@dataclass(frozen=True)
class StreamTimeouts:
    # A flight controller that has not answered after this, ignores the command.
    ack_s: float = 1.0
    attempts: int = 2
    watch_every_s: float = 1.0  # how often the achieved rates are judged


@dataclass(frozen=True)
class StreamRequest:
    """One message at one rate; 0 Hz stops it."""

    message: str
    msg_id: int
    rate_hz: float

    @property
    def interval_us(self) -> int:
        if self.rate_hz == 0:
            return INTERVAL_DISABLED_US
        return max(1, round(1e6 / self.rate_hz))


def message_id(name: str) -> int:
    """The MAVLink id of a message named as in the XML (``GPS2_RAW``)."""
    msg_id = getattr(mavlink2, f"MAVLINK_MSG_ID_{name}", None)
    if not isinstance(msg_id, int):
        raise ValueError(f"unknown MAVLink message {name!r} in stream_rates_hz")
    return msg_id


def stream_plan(
    overrides: Mapping[str, float], defaults: Mapping[str, float] = DEFAULT_RATES_HZ
) -> list[StreamRequest]:
    """The defaults with ``overrides`` merged over them (names are case-insensitive)."""
    merged = dict(defaults)
    for name, rate in overrides.items():
        merged[name.upper()] = rate
    plan = []
    for name, rate in merged.items():
        if not math.isfinite(rate) or rate < 0:
            raise ValueError(f"stream_rates_hz: {name} must be >= 0 Hz (0 stops it), not {rate}")
        plan.append(StreamRequest(name, message_id(name), float(rate)))
    return plan


def data_stream_rates(plan: list[StreamRequest]) -> dict[int, int]:
    """REQUEST_DATA_STREAM rates (whole Hz, 0 stops) per group: the fastest of its messages."""
    rates: dict[int, int] = {}
    for request in plan:
        group = _GROUP_OF.get(request.message)
        if group is None:
            continue
        whole = min(math.ceil(request.rate_hz), MAX_DATA_STREAM_HZ)
        rates[group] = max(rates.get(group, 0), whole)
    return rates


class StreamRequester:
    """Requests the plan when the link comes up, and again after every reconnect; in
    between, asks again for each message that arrives slower than asked."""

    def __init__(
        self,
        link: FcuLink,
        rates_hz: Mapping[str, float],
        timeouts: StreamTimeouts | None = None,
        watch: RateWatchSettings | None = None,
        clock: Callable[[], float] = time.monotonic,
        merger: RateMerger | None = None,
    ) -> None:
        self.link = link
        self.plan = stream_plan(rates_hz)
        # Shared with the MAVLink forward: what the agent asks for is merged with what the
        # GCSs on the link ask for, both ways (neither lowers the other's rate).
        self.merger = merger if merger is not None else RateMerger()
        self.merger.set_agent(self.plan)
        self.timeouts = timeouts or StreamTimeouts()
        self.method: Method | None = None  # how the last round was asked for
        self.rounds = 0
        self.watch = RateWatch(watch or RateWatchSettings(), clock)
        self._accepted: set[str] = set()  # SET_MESSAGE_INTERVAL accepted, this round
        self._wanted = asyncio.Event()
        self._asking = asyncio.Lock()  # one exchange of interval acks at a time

    async def run(self) -> None:
        self.link.state_listeners.append(self._on_link_change)
        self.link.listeners.append(self.watch.on_message)
        try:
            if self.link.up:
                self._wanted.set()
            async with asyncio.TaskGroup() as tasks:
                tasks.create_task(self._watch_rates())
                while True:
                    await self._wanted.wait()
                    self._wanted.clear()
                    try:
                        async with self._asking:
                            self.method = await self.request()
                            self.watch.watch(self._watched_requests())
                        self.rounds += 1
                    except ConnectionError as error:
                        # The link went down mid-round; the next "up" starts a new one.
                        log.info("stream requests interrupted: %s", error)
        finally:
            self.link.listeners.remove(self.watch.on_message)
            self.link.state_listeners.remove(self._on_link_change)

    def _watched_requests(self) -> list[StreamRequest]:
        """What the last round can be held to: messages the flight controller accepted a
        rate for, or (data streams) that a group carries."""
        if self.method == "message_interval":
            return [r for r in self.plan if r.message in self._accepted]
        return [r for r in self.plan if r.message in _GROUP_OF]

    async def _watch_rates(self) -> None:
        while True:
            await asyncio.sleep(self.timeouts.watch_every_s)
            if self.method is None or not self.link.up or self._wanted.is_set():
                continue
            slow = self.watch.due()
            if not slow:
                continue
            try:
                async with self._asking:
                    await self.restore(slow)
            except ConnectionError as error:
                log.info("stream requests interrupted: %s", error)

    async def restore(self, slow: list[StreamRequest]) -> None:
        """Ask again for messages that fell below their rate, as the last round asked."""
        if self.method == "data_stream":
            self.request_data_streams()
            return
        for request in slow:
            result = await self._set_interval(request)
            if result == mavlink2.MAV_RESULT_ACCEPTED:
                self.merger.note_interval(request.msg_id, self._merged(request).rate_hz)
            else:
                log.info(
                    "%s at %g Hz not set again: %s",
                    request.message,
                    request.rate_hz,
                    _result(result),
                )

    def _on_link_change(self, change: LinkChange) -> None:
        if change.up:
            self._wanted.set()

    async def request(self) -> Method:
        """One round: SET_MESSAGE_INTERVAL per message, or the fallback for all of them."""
        answered = False
        self._accepted.clear()
        self.merger.reset()  # the link is new: the flight controller's rates are its own
        for request in self.plan:
            result = await self._set_interval(request)
            if result == mavlink2.MAV_RESULT_UNSUPPORTED or (result is None and not answered):
                why = "refuses" if result is not None else "does not answer"
                log.warning(
                    "flight controller %s SET_MESSAGE_INTERVAL; asking with REQUEST_DATA_STREAM",
                    why,
                )
                self.request_data_streams()
                return "data_stream"
            answered = True
            if result == mavlink2.MAV_RESULT_ACCEPTED:
                self._accepted.add(request.message)
                self.merger.note_interval(request.msg_id, self._merged(request).rate_hz)
            else:
                # e.g. FAILED for a message this vehicle does not have (no second GPS)
                log.info(
                    "%s at %g Hz not set: %s", request.message, request.rate_hz, _result(result)
                )
        log.info("requested %d message rates with SET_MESSAGE_INTERVAL", len(self.plan))
        await self._request_events()
        return "message_interval"

    async def _request_events(self) -> None:
        modes = self.link.modes
        if modes is None or modes.autopilot != "px4":
            return  # ArduPilot sends its camera's CAMERA_FEEDBACK to every link unasked
        for name, rate in PX4_EVENT_RATES_HZ.items():
            request = StreamRequest(name, message_id(name), rate)
            result = await self._set_interval(request)
            if result == mavlink2.MAV_RESULT_ACCEPTED:
                log.info("asked PX4 for %s", name)
            else:
                log.warning("PX4 did not take the request for %s: %s", name, _result(result))

    async def _set_interval(self, request: StreamRequest) -> int | None:
        """The MAV_RESULT of one SET_MESSAGE_INTERVAL, or None if never acknowledged. The
        rate sent is the merged one: a GCS on the forward may need the message faster."""
        merged = self._merged(request)
        mine = self.link.source_system

        def is_ack(message: MavMessage) -> bool:
            # Ours, not a forwarded GCS's acknowledgement of its own request.
            return _is_interval_ack(message) and int(message.target_system) in (0, mine)

        for attempt in range(self.timeouts.attempts):
            self.link.send_command_long(
                mavlink2.MAV_CMD_SET_MESSAGE_INTERVAL,
                attempt,
                [merged.msg_id, merged.interval_us],
            )
            ack = await self.link.wait_for(is_ack, self.timeouts.ack_s)
            if ack is not None:
                return int(ack.result)
        return None

    def _merged(self, request: StreamRequest) -> StreamRequest:
        if request.rate_hz == 0:
            return request  # the agent stops it: a GCS's own request may start it again
        rate = self.merger.message_hz(request.msg_id)
        return StreamRequest(request.message, request.msg_id, max(rate, request.rate_hz))

    def request_data_streams(self) -> None:
        link = self.link
        target = (link.target_system or 1, link.target_component)
        for group, rate in self.merger.merged_groups(data_stream_rates(self.plan)).items():
            link.send(
                mavlink2.MAVLink_request_data_stream_message(
                    *target, group, rate, 1 if rate > 0 else 0
                )
            )
        if any(r.message == "HOME_POSITION" and r.rate_hz > 0 for r in self.plan):
            # not streamed in any group; ask once (ArduPilot also sends it when it changes)
            link.send_command_long(mavlink2.MAV_CMD_GET_HOME_POSITION, 0, [])
        ungrouped = [
            r.message
            for r in self.plan
            if r.message not in _GROUP_OF and r.message != "HOME_POSITION" and r.rate_hz > 0
        ]
        if ungrouped:
            log.info("without SET_MESSAGE_INTERVAL, no stream carries %s", ", ".join(ungrouped))


def _is_interval_ack(message: MavMessage) -> bool:
    return bool(
        message.get_type() == "COMMAND_ACK"
        and message.command == mavlink2.MAV_CMD_SET_MESSAGE_INTERVAL
    )


def _result(result: int | None) -> str:
    if result is None:
        return "no answer"
    entry = mavlink2.enums["MAV_RESULT"].get(result)
    return entry.name if entry is not None else f"MAV_RESULT {result}"


# -- one set of rates for everyone on the link ----------------------------------------

Ids = tuple[int, int]  # a GCS's (system id, component id)
# The groups MAV_DATA_STREAM_ALL sets on ArduPilot (handle_request_data_stream loops over
# every stream below STREAM_PARAMS): RAW_CONTROLLER has no messages on Copter, but is set.
ALL_GROUPS: tuple[int, ...] = (
    mavlink2.MAV_DATA_STREAM_RAW_SENSORS,
    mavlink2.MAV_DATA_STREAM_EXTENDED_STATUS,
    mavlink2.MAV_DATA_STREAM_RC_CHANNELS,
    mavlink2.MAV_DATA_STREAM_RAW_CONTROLLER,
    mavlink2.MAV_DATA_STREAM_POSITION,
    mavlink2.MAV_DATA_STREAM_EXTRA1,
    mavlink2.MAV_DATA_STREAM_EXTRA2,
    mavlink2.MAV_DATA_STREAM_EXTRA3,
)


@dataclass
class _Wants:
    groups: dict[int, int]  # REQUEST_DATA_STREAM group -> whole Hz (0: stopped)
    messages: dict[int, float]  # SET_MESSAGE_INTERVAL message id -> Hz (0: stopped)


@dataclass(frozen=True)
class IntervalAnswer:
    """What to do with a GCS's SET_MESSAGE_INTERVAL: pass its frame on (the flight
    controller answers it), or answer ACCEPTED in its place; and any rate the flight
    controller must be sent instead (the merged one), from the agent."""

    forward: bool
    send_hz: float | None = None


class RateMerger:
    """The rates the agent and every GCS sharing its link (through forwarding) ask for,
    merged, so the flight controller runs each stream at the highest rate anyone needs.

    A flight controller keeps one set of rates per link: on ArduPilot a REQUEST_DATA_STREAM
    sets the link's SRx_ rate of a group and the interval of each message in it, so a
    GCS's lower rate overrides the agent's, and the agent's higher one the GCS's, and the
    two fight (MAVProxy asks every ~15 s). Instead the forward hands every GCS's rate
    request here: a group is sent at the highest rate any party needs for it (the agent's
    need for a group is its fastest message in it), and only when that changes; a
    SET_MESSAGE_INTERVAL that asks for no more than is already set is answered by the
    forward. Used on the event loop only."""

    def __init__(self) -> None:
        self.agent: dict[int, float] = {}  # the agent's own: message id -> Hz
        self.clients: dict[Ids, _Wants] = {}
        self.sent_groups: dict[int, int] = {}  # what the flight controller was last sent
        self.sent_messages: dict[int, float] = {}
        self.absorbed = 0  # GCS requests that changed nothing and were not sent on

    def set_agent(self, plan: list[StreamRequest]) -> None:
        self.agent = {r.msg_id: r.rate_hz for r in plan}

    def reset(self) -> None:
        """The link came up again: the flight controller's rates are its defaults."""
        self.sent_groups.clear()
        self.sent_messages.clear()

    def _client(self, ids: Ids) -> _Wants:
        return self.clients.setdefault(ids, _Wants({}, {}))

    def _agent_group_hz(self, group: int) -> int:
        rates = [rate for msg_id, rate in self.agent.items() if _GROUP_OF_ID.get(msg_id) == group]
        return min(math.ceil(max(rates, default=0.0)), MAX_DATA_STREAM_HZ)

    def group_hz(self, group: int) -> int:
        """The rate a group needs: the fastest any party asks for."""
        clients = (wants.groups.get(group, 0) for wants in self.clients.values())
        return max(self._agent_group_hz(group), *clients, 0)

    def message_hz(self, msg_id: int, without: Ids | None = None) -> float:
        """The rate a message needs by SET_MESSAGE_INTERVAL (leaving out one GCS)."""
        rates = [
            wants.messages.get(msg_id, 0.0) for ids, wants in self.clients.items() if ids != without
        ]
        return max(self.agent.get(msg_id, 0.0), *rates, 0.0)

    def data_stream(self, ids: Ids, group: int, rate_hz: int, start: bool) -> dict[int, int]:
        """A GCS's REQUEST_DATA_STREAM: the groups whose merged rate changed, to send."""
        wants = self._client(ids)
        groups = ALL_GROUPS if group == mavlink2.MAV_DATA_STREAM_ALL else (group,)
        for one in groups:
            wants.groups[one] = rate_hz if start else 0
        changed = self.changed_groups(groups)
        if not changed:
            self.absorbed += 1
        return changed

    def changed_groups(self, groups: tuple[int, ...] | None = None) -> dict[int, int]:
        """The merged rates of these groups (all known ones) that differ from what the
        flight controller was sent; noted as sent."""
        changed = {}
        for group in groups if groups is not None else ALL_GROUPS:
            rate = self.group_hz(group)
            if rate == 0 and group not in self.sent_groups:
                continue  # nobody wants it and it was never set: leave the default
            if self.sent_groups.get(group) != rate:
                changed[group] = rate
                self.sent_groups[group] = rate
        return changed

    def known_hz(self, msg_id: int) -> float | None:
        """The rate the flight controller was last set to send a message at, if known."""
        if msg_id in self.sent_messages:
            return self.sent_messages[msg_id]
        group = _GROUP_OF_ID.get(msg_id)
        return None if group is None else self.sent_groups.get(group)

    def message_interval(self, ids: Ids, msg_id: int, interval_us: float) -> IntervalAnswer:
        """A GCS's SET_MESSAGE_INTERVAL (param2: > 0 microseconds, 0 the default, < 0 stop)."""
        wants = self._client(ids)
        if interval_us == 0:
            wants.messages.pop(msg_id, None)  # its default: no need of its own
        else:
            wants.messages[msg_id] = 1e6 / interval_us if interval_us > 0 else 0.0
        asked = wants.messages.get(msg_id)
        others = self.message_hz(msg_id, without=ids)
        if others == 0 or (asked is not None and asked > others):
            # Nobody else needs it, or the GCS needs the most: its own request, which the
            # flight controller answers, unless that rate is set already.
            if asked is not None and self.known_hz(msg_id) == asked:
                self.absorbed += 1
                return IntervalAnswer(forward=False)
            if asked is None:
                self.sent_messages.pop(msg_id, None)
            else:
                self.sent_messages[msg_id] = asked
            return IntervalAnswer(forward=True)
        # Another party needs at least as much: the GCS gets at least what it asked for.
        if self.known_hz(msg_id) == others:
            self.absorbed += 1
            return IntervalAnswer(forward=False)
        self.sent_messages[msg_id] = others
        return IntervalAnswer(forward=False, send_hz=others)

    def merged_groups(self, agent_rates: dict[int, int]) -> dict[int, int]:
        """The agent's REQUEST_DATA_STREAM rates with every GCS's merged in, noted as sent."""
        merged = {group: max(rate, self.group_hz(group)) for group, rate in agent_rates.items()}
        self.sent_groups.update(merged)
        return merged

    def note_interval(self, msg_id: int, rate_hz: float) -> None:
        """The agent set a message's interval itself (and it was accepted)."""
        self.sent_messages[msg_id] = rate_hz


_GROUP_OF_ID = {
    getattr(mavlink2, f"MAVLINK_MSG_ID_{name}"): group
    for name, group in _GROUP_OF.items()
    if hasattr(mavlink2, f"MAVLINK_MSG_ID_{name}")
}
