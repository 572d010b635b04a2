"""Rate requests on the simulator: REQUEST_DATA_STREAM groups, SET_MESSAGE_INTERVAL refused
or ignored as an old flight controller would, and the optional second GPS."""

from __future__ import annotations

from typing import Any

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from simulator import DEFAULT_HOME, Copter, ListenAddress, SimulatorConfig
from simulator.config import MessageIntervalSupport, parse_args
from simulator.mavconst import MavCmd, MavResult, MsgId
from simulator.mavlink.commands import MessageHandler, Reply
from simulator.mavlink.message_context import SecondGps
from simulator.mavlink.streams import (
    DataStream,
    StreamRequests,
    StreamSchedule,
    request_data_stream,
)
from simulator.mavlink.telemetry import DEFAULT_RATES_HZ, GPS2_RAW, TelemetryBuilder
from tests.support.simulators import mavlink_client, serving, wait_for

SYSID = 7  # the system id tests.simulator.test_sim_server's helpers expect


class Peer:
    """The request layer of a simulated vehicle, fed messages as if off the wire."""

    def __init__(
        self, message_interval: MessageIntervalSupport = "supported", gps2: SecondGps | None = None
    ) -> None:
        self.copter = Copter(DEFAULT_HOME)
        self.telemetry = TelemetryBuilder(self.copter, boot_epoch_s=1_700_000_000.0, gps2=gps2)
        handler = MessageHandler(self.copter, self.telemetry, SYSID)
        self.requests = StreamRequests(handler, message_interval)
        self.streams = StreamSchedule(DEFAULT_RATES_HZ, now=0.0)
        self._gcs = mavlink2.MAVLink(None, srcSystem=255, srcComponent=190)
        self._parser = mavlink2.MAVLink(None)

    def send(self, message: Any) -> list[Reply]:
        [decoded] = self._parser.parse_buffer(message.pack(self._gcs))
        return self.requests.handle(decoded, self.streams, now=0.0)

    def set_interval(self, msg_id: int, interval_us: float) -> list[Reply]:
        return self.send(
            mavlink2.MAVLink_command_long_message(
                SYSID, 1, MavCmd.SET_MESSAGE_INTERVAL, 0, msg_id, interval_us, 0, 0, 0, 0, 0
            )
        )

    def data_stream(self, stream: int, rate: int, start_stop: int = 1, target: int = SYSID) -> None:
        request = mavlink2.MAVLink_request_data_stream_message(target, 1, stream, rate, start_stop)
        assert self.send(request) == []  # REQUEST_DATA_STREAM has no acknowledgement


def ack_results(replies: list[Reply]) -> list[int]:
    return [int(r.message.result) for r in replies if r.message.get_type() == "COMMAND_ACK"]


def test_request_data_stream_sets_a_groups_rate() -> None:
    peer = Peer()
    peer.data_stream(DataStream.EXTENDED_STATUS, 2)
    for msg_id in (MsgId.SYS_STATUS, MsgId.GPS_RAW_INT, MsgId.MISSION_CURRENT, GPS2_RAW):
        assert peer.streams.interval(msg_id) == 0.5
    assert peer.streams.interval(MsgId.ATTITUDE) == 0.1  # other groups keep their rates
    peer.data_stream(DataStream.EXTRA1, 4)
    assert peer.streams.interval(MsgId.ATTITUDE) == 0.25


def test_request_data_stream_stops_and_starts_everything() -> None:
    peer = Peer()
    peer.data_stream(DataStream.ALL, 0, start_stop=0)
    for msg_id in (MsgId.ATTITUDE, MsgId.GLOBAL_POSITION_INT, MsgId.VFR_HUD, MsgId.SYS_STATUS):
        assert peer.streams.interval(msg_id) is None
    # groupless messages are untouched, as in ArduPilot
    assert peer.streams.interval(MsgId.HEARTBEAT) == 1.0
    assert peer.streams.interval(MsgId.HOME_POSITION) == 2.0
    peer.data_stream(DataStream.ALL, 5)
    assert peer.streams.interval(MsgId.GLOBAL_POSITION_INT) == 0.2
    assert peer.streams.interval(MsgId.BATTERY_STATUS) == 0.2
    peer.data_stream(DataStream.POSITION, 0)  # start with rate 0 is a stop too
    assert peer.streams.interval(MsgId.GLOBAL_POSITION_INT) is None


def test_request_data_stream_ignores_what_it_does_not_understand() -> None:
    peer = Peer()
    peer.data_stream(DataStream.EXTRA1, 1, start_stop=2)  # neither start nor stop
    peer.data_stream(DataStream.RAW_SENSORS, 1)  # a group the simulator has nothing in
    peer.data_stream(DataStream.EXTRA1, 1, target=SYSID + 1)  # another vehicle's
    assert peer.streams.interval(MsgId.ATTITUDE) == 0.1


def test_request_data_stream_on_the_schedule_directly() -> None:
    schedule = StreamSchedule(DEFAULT_RATES_HZ, now=0.0)
    request_data_stream(schedule, DataStream.EXTRA2, 20, 1, now=0.0)
    assert schedule.interval(MsgId.VFR_HUD) == 0.05
    assert MsgId.VFR_HUD in schedule.due(0.0)  # a changed rate starts at once
    assert MsgId.VFR_HUD not in schedule.due(0.04)
    assert MsgId.VFR_HUD in schedule.due(0.05)


@pytest.mark.parametrize(
    ("support", "expected"),
    [("supported", [MavResult.ACCEPTED]), ("unsupported", [MavResult.UNSUPPORTED]), ("silent", [])],
)
def test_set_message_interval_as_old_flight_controllers_answer_it(
    support: MessageIntervalSupport, expected: list[int]
) -> None:
    peer = Peer(support)
    assert ack_results(peer.set_interval(MsgId.ATTITUDE, 500_000)) == expected
    changed = support == "supported"
    assert peer.streams.interval(MsgId.ATTITUDE) == (0.5 if changed else 0.1)
    # REQUEST_DATA_STREAM works whatever the answer to SET_MESSAGE_INTERVAL
    peer.data_stream(DataStream.EXTRA1, 2)
    assert peer.streams.interval(MsgId.ATTITUDE) == 0.5


def test_gps2_rate_can_be_set_before_the_receiver_is_fitted() -> None:
    peer = Peer()
    assert GPS2_RAW not in peer.telemetry.supported
    assert ack_results(peer.set_interval(GPS2_RAW, 200_000)) == [MavResult.ACCEPTED]
    assert peer.streams.interval(GPS2_RAW) == 0.2
    assert peer.telemetry.build(GPS2_RAW) is None  # nothing to send yet
    peer.telemetry.gps2 = SecondGps()
    message = peer.telemetry.build(GPS2_RAW)
    assert (message.fix_type, message.satellites_visible) == (6, 18)
    assert ack_results(peer.set_interval(GPS2_RAW, -1)) == [MavResult.ACCEPTED]
    assert peer.streams.interval(GPS2_RAW) is None


def test_the_second_gps_reports_the_true_position() -> None:
    peer = Peer(gps2=SecondGps(mavlink2.GPS_FIX_TYPE_RTK_FLOAT, 15))
    assert GPS2_RAW in peer.telemetry.supported
    encoder = mavlink2.MAVLink(None, srcSystem=SYSID, srcComponent=1)
    [decoded] = mavlink2.MAVLink(None).parse_buffer(peer.telemetry.build(GPS2_RAW).pack(encoder))
    assert decoded.get_type() == "GPS2_RAW"
    assert (decoded.fix_type, decoded.satellites_visible) == (5, 15)
    here = peer.copter.position()
    assert (decoded.lat, decoded.lon) == (round(here.lat * 1e7), round(here.lon * 1e7))


def test_command_line_options() -> None:
    config = parse_args(["--gps2", "rtk-fixed", "--message-interval", "unsupported"])
    assert config.gps2_fix == mavlink2.GPS_FIX_TYPE_RTK_FIXED
    assert config.message_interval == "unsupported"
    defaults = parse_args([])
    assert (defaults.gps2_fix, defaults.message_interval) == (None, "supported")
    with pytest.raises(ValueError, match="GPS_FIX_TYPE"):
        SimulatorConfig(gps2_fix=12)


def test_over_tcp_refused_interval_then_data_streams() -> None:
    config = SimulatorConfig(
        listen=ListenAddress("tcp", "127.0.0.1", 0),
        system_id=SYSID,
        gps2_fix=mavlink2.GPS_FIX_TYPE_RTK_FIXED,
        message_interval="unsupported",
    )
    with (
        serving(config) as (_server, address),
        mavlink_client(f"tcp:127.0.0.1:{address.port}") as gcs,
    ):
        wait_for(gcs, ["HEARTBEAT"], lambda m: True, 5, "a heartbeat")
        gcs.mav.command_long_send(
            SYSID, 1, MavCmd.SET_MESSAGE_INTERVAL, 0, MsgId.ATTITUDE, 1e6, 0, 0, 0, 0, 0
        )
        ack = wait_for(
            gcs,
            ["COMMAND_ACK"],
            lambda m: m.command == MavCmd.SET_MESSAGE_INTERVAL,
            5,
            "the refusal",
        )
        assert ack.result == MavResult.UNSUPPORTED
        gcs.mav.request_data_stream_send(SYSID, 1, DataStream.EXTRA1, 4, 1)
        gcs.mav.request_data_stream_send(SYSID, 1, DataStream.EXTENDED_STATUS, 2, 1)
        # messages are handled in order: the interval read back reflects the requests
        for msg_id, interval_us in ((MsgId.ATTITUDE, 250_000), (GPS2_RAW, 500_000)):
            gcs.mav.command_long_send(
                SYSID, 1, MavCmd.GET_MESSAGE_INTERVAL, 0, msg_id, 0, 0, 0, 0, 0, 0
            )
            reply = wait_for(
                gcs,
                ["MESSAGE_INTERVAL"],
                lambda m, msg_id=msg_id: m.message_id == msg_id,
                5,
                f"the interval of message {msg_id}",
            )
            assert reply.interval_us == interval_us
        gps2 = wait_for(gcs, ["GPS2_RAW"], lambda m: True, 5, "the second GPS")
        assert gps2.fix_type == mavlink2.GPS_FIX_TYPE_RTK_FIXED
