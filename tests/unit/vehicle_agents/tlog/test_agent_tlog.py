from __future__ import annotations

import logging
import threading
from collections.abc import Iterator
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from tests.support.mavutil_state import mavutil_in_mavlink2, read_tlog
from vehicle_agents.tlog.recorder import TlogRecorder, TlogUploadError, upload_tlog

T0 = 1_700_000_000.0  # 2023-11-14T22:13:20Z
ARMED = mavlink2.MAV_MODE_FLAG_SAFETY_ARMED | mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
DISARMED = mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED


class Wire:
    """Messages as the agent receives them: packed by a sender, parsed from bytes."""

    def __init__(self) -> None:
        self._senders: dict[tuple[int, int], Any] = {}
        self._parser = mavlink2.MAVLink(None)

    def receive(self, message: Any, system: int = 1, component: int = 1) -> Any:
        sender = self._senders.setdefault(
            (system, component), mavlink2.MAVLink(None, srcSystem=system, srcComponent=component)
        )
        (parsed,) = self._parser.parse_buffer(message.pack(sender))
        return parsed


def heartbeat(base_mode: int) -> Any:
    return mavlink2.MAVLink_heartbeat_message(
        mavlink2.MAV_TYPE_QUADROTOR, mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA, base_mode, 4, 4, 3
    )


def gcs_heartbeat() -> Any:
    return mavlink2.MAVLink_heartbeat_message(
        mavlink2.MAV_TYPE_GCS, mavlink2.MAV_AUTOPILOT_INVALID, 0, 0, 0, 3
    )


def position(index: int) -> Any:
    return mavlink2.MAVLink_global_position_int_message(
        index * 100, 473977420 + index, 85455940 - index, 488000 + index, index * 10, 1, 2, 3, 9000
    )


@pytest.fixture
def mavutil(monkeypatch: pytest.MonkeyPatch) -> ModuleType:
    return mavutil_in_mavlink2(monkeypatch)


def test_one_flight_is_one_file_of_what_was_received(tmp_path: Path, mavutil: ModuleType) -> None:
    wire = Wire()
    recorder = TlogRecorder(tmp_path, "alpha-1")
    before = [(heartbeat(DISARMED), T0, 1), (position(0), T0 + 0.5, 1)]
    flight = [
        (heartbeat(ARMED), T0 + 1.0, 1),
        *[(position(i), T0 + 1.0 + i * 0.1, 1) for i in range(1, 6)],
        (mavlink2.MAVLink_statustext_message(6, b"Takeoff"), T0 + 1.55, 1),
        (gcs_heartbeat(), T0 + 1.6, 255),  # never armed: it must not end the flight
        (position(6), T0 + 1.7, 1),
        (heartbeat(DISARMED), T0 + 2.0, 1),
    ]
    after = [(position(7), T0 + 2.1, 1), (heartbeat(DISARMED), T0 + 3.0, 1)]

    for message, at, system in before:
        recorder.record(wire.receive(message, system), at)
        assert recorder.recording is None
    for message, at, system in flight[:-1]:
        recorder.record(wire.receive(message, system), at)
        assert recorder.recording is not None
    for message, at, system in [flight[-1], *after]:
        recorder.record(wire.receive(message, system), at)
        assert recorder.recording is None

    assert recorder.recording is None
    assert list(recorder.finished) == [tmp_path / "alpha-1_20231114T221321.tlog"]
    read = read_tlog(mavutil, recorder.finished[0])
    assert [m.get_type() for m in read] == [m.get_type() for m, _, _ in flight]
    assert [m._timestamp for m in read] == pytest.approx([at for _, at, _ in flight], abs=1e-6)
    assert [m.get_msgbuf() for m in read] == [m.get_msgbuf() for m, _, _ in flight]
    assert read[-2].lat == 473977426
    assert read[-3].get_srcSystem() == 255


def test_each_flight_gets_its_own_file(tmp_path: Path) -> None:
    wire = Wire()
    recorder = TlogRecorder(tmp_path / "logs", "alpha/1")

    for at in (T0, T0 + 0.5):  # twice in the same second
        recorder.record(wire.receive(heartbeat(ARMED)), at)
        recorder.record(wire.receive(position(1)), at + 0.1)
        recorder.record(wire.receive(heartbeat(DISARMED)), at + 0.2)

    assert [p.name for p in recorder.finished] == [
        "alpha_1_20231114T221320.tlog",
        "alpha_1_20231114T221320_1.tlog",
    ]
    assert all(p.stat().st_size > 0 for p in recorder.finished)


def test_a_flight_already_armed_at_start_is_recorded_and_close_finishes_it(
    tmp_path: Path,
) -> None:
    wire = Wire()
    recorder = TlogRecorder(tmp_path, "alpha-1")

    recorder.record(wire.receive(heartbeat(ARMED)), T0)
    recorder.record(wire.receive(position(1)), T0 + 0.1)
    assert recorder.recording is not None
    assert not recorder.finished
    recorder.close()

    assert recorder.recording is None
    assert len(recorder.finished) == 1
    assert recorder.finished[0].stat().st_size > 0


def test_writing_stops_past_max_bytes_and_says_so_once(
    tmp_path: Path, mavutil: ModuleType, caplog: pytest.LogCaptureFixture
) -> None:
    wire = Wire()
    first = wire.receive(heartbeat(ARMED))
    one_position = 8 + len(wire.receive(position(0)).get_msgbuf())
    limit = 8 + len(first.get_msgbuf()) + 3 * one_position
    recorder = TlogRecorder(tmp_path, "alpha-1", max_bytes=limit)

    with caplog.at_level(logging.WARNING, logger="vehicle_agents.tlog.recorder"):
        recorder.record(first, T0)
        for i in range(10):
            recorder.record(wire.receive(position(i)), T0 + i * 0.1)
        recorder.record(wire.receive(heartbeat(DISARMED)), T0 + 2)

    (path,) = recorder.finished
    assert path.stat().st_size == limit
    assert [m.get_type() for m in read_tlog(mavutil, path)] == ["HEARTBEAT"] + [
        "GLOBAL_POSITION_INT"
    ] * 3
    assert len([r for r in caplog.records if "stopped" in r.getMessage()]) == 1


# -- upload ------------------------------------------------------------------


class RecordingServer(ThreadingHTTPServer):
    status = 201
    requests: list[tuple[str, str, dict[str, str], bytes]]


class RecordingHandler(BaseHTTPRequestHandler):
    server: RecordingServer

    def do_POST(self) -> None:
        body = self.rfile.read(int(self.headers.get("Content-Length", "0")))
        self._answer(body)

    def do_GET(self) -> None:
        self._answer(b"")

    def _answer(self, body: bytes) -> None:
        self.server.requests.append((self.command, self.path, dict(self.headers), body))
        reply = b'{"detail": "no"}'
        self.send_response(self.server.status)
        if self.server.status == 302:
            self.send_header("Location", "/elsewhere")
        self.send_header("Content-Length", str(len(reply)))
        self.end_headers()
        self.wfile.write(reply)

    def log_message(self, format: str, *args: Any) -> None:
        pass


@pytest.fixture
def server() -> Iterator[RecordingServer]:
    http = RecordingServer(("127.0.0.1", 0), RecordingHandler)
    http.requests = []
    thread = threading.Thread(target=http.serve_forever, kwargs={"poll_interval": 0.05})
    thread.start()
    try:
        yield http
    finally:
        http.shutdown()
        http.server_close()
        thread.join()


def _url(server: RecordingServer) -> str:
    return f"http://127.0.0.1:{server.server_address[1]}/api/v1/vehicles/alpha-1/tlogs"


def test_upload_posts_the_file_with_its_headers(tmp_path: Path, server: RecordingServer) -> None:
    path = tmp_path / "alpha-1_20231114T221321.tlog"
    content = bytes(range(256)) * 12_000  # 3 MB, more than any single socket write
    path.write_bytes(content)

    upload_tlog(path, _url(server), "secret-token")

    ((method, url_path, headers, body),) = server.requests
    assert (method, url_path) == ("POST", "/api/v1/vehicles/alpha-1/tlogs")
    assert headers["Content-Type"] == "application/octet-stream"
    assert headers["Authorization"] == "Bearer secret-token"
    assert headers["X-Filename"] == "alpha-1_20231114T221321.tlog"
    assert headers["Content-Length"] == str(len(content))
    assert body == content


@pytest.mark.parametrize("status", [401, 413, 500, 302])
def test_a_non_2xx_answer_raises(tmp_path: Path, server: RecordingServer, status: int) -> None:
    path = tmp_path / "f.tlog"
    path.write_bytes(b"x" * 100)
    server.status = status

    with pytest.raises(TlogUploadError, match=f"HTTP {status}") as raised:
        upload_tlog(path, _url(server), "t")

    assert raised.value.status == status
    assert [request[0] for request in server.requests] == ["POST"]  # no redirect followed


def test_only_http_urls_are_accepted(tmp_path: Path) -> None:
    path = tmp_path / "f.tlog"
    path.write_bytes(b"x")

    with pytest.raises(ValueError, match="http"):
        upload_tlog(path, f"file://{tmp_path}/copy", "t")
