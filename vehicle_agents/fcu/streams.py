"""Telemetry shaping: ask the flight controller for the messages the agent uses, at the
rates it uses them, each time the link comes up.

MAV_CMD_SET_MESSAGE_INTERVAL sets one message's rate and is acknowledged. Flight
controllers that answer it UNSUPPORTED, or not at all (old ArduPilot, some radios that
drop COMMAND_LONG), get the older REQUEST_DATA_STREAM instead: one rate per group of
messages (ArduPilot's SRx_ parameters), with no acknowledgement.

Another GCS on the same link can change those rates at any time; `RateWatch`
(`stream_watch.py`) measures what arrives, and the requester asks again for any message
that falls below its rate, the same way it asked the first time.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Literal

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from vehicle_agents.fcu.link import FcuLink
from vehicle_agents.fcu.messages import LinkChange, MavMessage
from vehicle_agents.fcu.rate_merger import RateMerger
from vehicle_agents.fcu.stream_plan import (
    GROUP_OF,
    PX4_EVENT_RATES_HZ,
    StreamRequest,
    data_stream_rates,
    message_id,
    stream_plan,
)
from vehicle_agents.fcu.stream_watch import RateWatch, RateWatchSettings

log = logging.getLogger(__name__)


Method = Literal["message_interval", "data_stream"]


@dataclass(frozen=True)
class StreamTimeouts:
    # A flight controller that has not answered after this, ignores the command.
    ack_s: float = 1.0
    attempts: int = 2
    watch_every_s: float = 1.0  # how often the achieved rates are judged


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
        return [r for r in self.plan if r.message in GROUP_OF]

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
            if r.message not in GROUP_OF and r.message != "HOME_POSITION" and r.rate_hz > 0
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
