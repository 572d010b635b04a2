"""Two agents with one vehicle id: the first keeps it, the second is refused and stops.

Real agent processes, real flight-controller peers on TCP, a real hub. A cloned SD card
is two aircraft with one id (and one token); a network cut leaves the hub holding the
agent's old, half-dead connection while the same agent comes back.
"""

from __future__ import annotations

import contextlib
import os
import signal
import socket
import subprocess
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest
from pymavlink.dialects.v20 import common as mavlink2

from tests.support.api import api_client
from tests.support.mavlink_peer import ScriptedFlightController
from tests.support.processes import agent_process
from tests.support.tcp_proxy import CuttableProxy
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher, connected
from vehicle_agents.cli import EXIT_VEHICLE_ID_IN_USE

pytestmark = pytest.mark.integration

Enrol = Callable[[str], str]


def _events(api: httpx.Client, vehicle: str, kind: str) -> list[dict[str, Any]]:
    # Not filtered by vehicle in the query: that is a 404 until the vehicle first connects.
    page = api.get("/api/v1/events", params={"kind": kind})
    assert page.status_code == 200, page.text
    return [event for event in page.json()["events"] if event["vehicle_id"] == vehicle]


class _Line:
    """One proxied connection's filter, which a cut can silence."""

    def __init__(self, agent_side: socket.socket) -> None:
        self.agent_side = agent_side
        self.severed = False

    def __call__(self, data: bytes) -> bytes:
        return b"" if self.severed else data


class AgentSideCut(CuttableProxy):
    """Between agent and hub: ``cut_agent_side()`` closes the agent's end of every
    connection (it notices at once and reconnects) and leaves the hub's end open and
    silent, as after a network cut the hub has not noticed yet."""

    def __init__(self, target: tuple[str, int]) -> None:
        super().__init__(target)
        self._lines: list[_Line] = []

    def filters(self) -> tuple[_Line, _Line]:
        with self._lock:
            line = _Line(self._sockets[-2])  # _accept has just added (client, upstream)
            self._lines.append(line)
        return line, line

    def cut_agent_side(self) -> None:
        with self._lock:
            lines, self._lines = self._lines, []
        for line in lines:
            line.severed = True
            with contextlib.suppress(OSError):
                line.agent_side.shutdown(socket.SHUT_RDWR)

    def _pump(self, source: socket.socket, sink: socket.socket, forward: Any) -> None:  # type: ignore[override]
        with contextlib.suppress(OSError):
            while data := source.recv(65536):
                if out := forward(data):
                    sink.sendall(out)
        if not (isinstance(forward, _Line) and forward.severed):
            for each in (source, sink):  # an ordinary end goes through to both sides
                with contextlib.suppress(OSError):
                    each.shutdown(socket.SHUT_RDWR)


@contextlib.contextmanager
def stopped(process: subprocess.Popen[bytes]) -> Iterator[None]:
    """The process frozen (SIGSTOP): its sockets stay open and it answers nothing."""
    os.kill(process.pid, signal.SIGSTOP)
    try:
        yield
    finally:
        os.kill(process.pid, signal.SIGCONT)


def test_a_second_agent_with_the_same_id_is_refused_and_stops(
    hub: str, admin_token: str, enrol: Enrol, tmp_path: Path
) -> None:
    token = enrol("twin")  # a cloned SD card: same id, same token, another aircraft
    with (
        ScriptedFlightController(system_id=1) as first_fcu,
        ScriptedFlightController(system_id=2, autopilot=mavlink2.MAV_AUTOPILOT_PX4) as clone_fcu,
        agent_process(hub, token, "twin", first_fcu.port, tmp_path) as first,
        FleetWatcher(hub, admin_token) as watcher,
    ):
        watcher.wait_until(connected("twin"), 30, "the first agent to connect")
        (tmp_path / "clone").mkdir()
        with agent_process(hub, token, "twin", clone_fcu.port, tmp_path / "clone") as clone:
            assert clone.wait(30) == EXIT_VEHICLE_ID_IN_USE, "the clone gives up"
        log = (tmp_path / "clone" / "twin.log").read_text()
        assert "refused vehicle id 'twin'" in log
        assert "clash" in log
        assert "--vehicle-id" in log
        # The operator sees it as it happens, on the dashboards' live feed.
        watcher.wait_until(
            lambda _: any(
                e["vehicle_id"] == "twin" and e["kind"] == "id_clash" and e["severity"] == 3
                for e in watcher.events
            ),
            10,
            "the clash on the live feed",
        )
        with api_client(hub, admin_token) as api:
            poll_until(lambda: _events(api, "twin", "id_clash"), 10, "the clash event")
            [clash] = _events(api, "twin", "id_clash")
            assert clash["severity"] == 3
            assert "refused a second agent" in clash["text"]
            # The first agent was never kicked off, and the vehicle is still its aircraft.
            assert len(_events(api, "twin", "link_up")) == 1
            assert _events(api, "twin", "link_down") == []
            vehicle = api.get("/api/v1/vehicles/twin").json()
        assert vehicle["connected"] is True
        assert vehicle["autopilot"] == "ardupilot"
        assert first.poll() is None


def test_the_same_agent_gets_past_its_half_dead_connection(
    hub: str, admin_token: str, enrol: Enrol, tmp_path: Path
) -> None:
    port = int(hub.rsplit(":", 1)[1])
    with (
        ScriptedFlightController(system_id=1) as fcu,
        AgentSideCut(("127.0.0.1", port)) as proxy,
        agent_process(
            f"http://127.0.0.1:{proxy.port}", enrol("v1"), "v1", fcu.port, tmp_path
        ) as agent,
        api_client(hub, admin_token) as api,
    ):
        poll_until(lambda: len(_events(api, "v1", "link_up")) == 1, 30, "the first link")
        proxy.cut_agent_side()  # the hub still holds the old connection, silent
        poll_until(lambda: len(_events(api, "v1", "link_up")) == 2, 30, "the reconnection")
        assert _events(api, "v1", "id_clash") == []
        assert agent.poll() is None
        assert api.get("/api/v1/vehicles/v1").json()["connected"] is True


def test_a_new_agent_takes_over_from_one_that_no_longer_answers(
    hub: str, admin_token: str, enrol: Enrol, tmp_path: Path
) -> None:
    token = enrol("v1")
    with (
        ScriptedFlightController(system_id=1) as fcu,
        ScriptedFlightController(system_id=1) as same_fcu,  # its own port, same aircraft
        agent_process(hub, token, "v1", fcu.port, tmp_path) as frozen,
        api_client(hub, admin_token) as api,
    ):
        poll_until(lambda: len(_events(api, "v1", "link_up")) == 1, 30, "the first link")
        # Hung, or its computer lost power behind a router: its connection stays open.
        with stopped(frozen):
            (tmp_path / "new").mkdir()
            with agent_process(hub, token, "v1", same_fcu.port, tmp_path / "new") as newcomer:
                poll_until(lambda: len(_events(api, "v1", "link_up")) == 2, 30, "the takeover")
                assert newcomer.poll() is None
                assert _events(api, "v1", "id_clash") == []
                assert api.get("/api/v1/vehicles/v1").json()["connected"] is True
            frozen.kill()
