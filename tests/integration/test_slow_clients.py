"""Slow clients cannot hold the hub (13.13): a trickled body is cut off with 408 and
its connection closed; past the connection limit, requests get 503 at once. Real
sockets against a real `gcs hub` process."""

from __future__ import annotations

import selectors
import socket
import time
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager, suppress
from pathlib import Path

import httpx
import pytest

from gcs.launcher import FleetPlan, LocalFleet, free_port
from tests.support.hubs import TEST_HUB_ENV
from tests.support.waiting import poll_until

pytestmark = pytest.mark.integration

SLOW_POST = (
    b"POST /api/v1/auth/token HTTP/1.1\r\nHost: hub\r\n"
    b"Content-Type: application/x-www-form-urlencoded\r\nContent-Length: 1000\r\n\r\nu"
)


@contextmanager
def hub_process(tmp_path: Path, **env: str) -> Iterator[LocalFleet]:
    plan = FleetPlan(vehicles=0, port=free_port(), data_dir=tmp_path)
    with LocalFleet(plan) as fleet:
        fleet.start(hub_env={**TEST_HUB_ENV, **env})
        fleet.wait_until_ready()
        yield fleet


def _open_fds(fleet: LocalFleet) -> int:
    return len(list(Path(f"/proc/{fleet.processes[0].process.pid}/fd").iterdir()))


def _slow_sockets(stack: ExitStack, port: int, count: int) -> list[socket.socket]:
    sockets = []
    for _ in range(count):
        client = stack.enter_context(socket.create_connection(("127.0.0.1", port), timeout=5))
        client.sendall(SLOW_POST)  # headers, then one byte of a 1000-byte body
        sockets.append(client)
    return sockets


def test_a_trickled_body_is_cut_off_with_408_and_the_connection_closed(tmp_path: Path) -> None:
    with hub_process(tmp_path, GCS_BODY_TIMEOUT_S="1", GCS_BODY_MIN_RATE_BPS="100") as fleet:
        baseline = _open_fds(fleet)
        with ExitStack() as stack:
            sockets = _slow_sockets(stack, fleet.plan.port, 50)
            answers = {client: b"" for client in sockets}
            selector = stack.enter_context(selectors.DefaultSelector())
            for client in sockets:
                selector.register(client, selectors.EVENT_READ)
            started = time.monotonic()
            open_ones = set(sockets)
            while open_ones and time.monotonic() - started < 15:
                for client in open_ones:  # a byte every 0.3 s each: far under 100 bytes/s
                    with suppress(OSError):
                        client.send(b"x")
                for key, _ in selector.select(timeout=0.3):
                    client = key.fileobj
                    assert isinstance(client, socket.socket)
                    try:
                        chunk = client.recv(4096)
                    except ConnectionResetError:
                        # Closed while bytes were still coming: TCP resets, and may drop
                        # the 408 before it is read. Closed is what counts.
                        chunk = b""
                    answers[client] += chunk
                    if not chunk:  # the hub closed it
                        selector.unregister(client)
                        open_ones.discard(client)
            elapsed = time.monotonic() - started
        assert not open_ones, f"{len(open_ones)} slow connections still held after {elapsed:.0f} s"
        answered = [answer for answer in answers.values() if answer]
        assert answered, "no 408 was read at all"
        assert all(answer.startswith(b"HTTP/1.1 408") for answer in answered)
        assert b"request body too slow" in answered[0]
        assert elapsed < 10
        # Their file descriptors are given back.
        poll_until(lambda: _open_fds(fleet) <= baseline + 2, 10, "the hub's descriptors freed")


def test_past_the_connection_limit_requests_get_503_at_once(tmp_path: Path) -> None:
    with hub_process(tmp_path, GCS_MAX_CONNECTIONS="5", GCS_BODY_TIMEOUT_S="60") as fleet:
        url = f"{fleet.plan.hub_http}/api/v1/health"
        with ExitStack() as stack:
            _slow_sockets(stack, fleet.plan.port, 5)
            refused = httpx.get(url, timeout=5)
            assert refused.status_code == 503
        poll_until(lambda: httpx.get(url, timeout=5).status_code == 200, 10, "served again")


def test_a_large_body_at_a_fair_rate_is_not_cut_off(tmp_path: Path) -> None:
    """The timeout grows with what arrived: a 64 KB body over 3 s passes a 1 s grace."""
    with hub_process(tmp_path, GCS_BODY_TIMEOUT_S="1", GCS_BODY_MIN_RATE_BPS="8192") as fleet:
        body = b"username=admin&password=" + b"p" * (64 * 1024 - 24)
        with socket.create_connection(("127.0.0.1", fleet.plan.port), timeout=10) as client:
            client.sendall(
                b"POST /api/v1/auth/token HTTP/1.1\r\nHost: hub\r\nConnection: close\r\n"
                b"Content-Type: application/x-www-form-urlencoded\r\n"
                b"Content-Length: " + str(len(body)).encode() + b"\r\n\r\n"
            )
            for offset in range(0, len(body), 8 * 1024):  # 8 KB every 0.375 s: 21 KB/s
                client.sendall(body[offset : offset + 8 * 1024])
                time.sleep(0.375)  # pacing the upload, not waiting for anything
            answer = b""
            while chunk := client.recv(4096):
                answer += chunk
    # Over the hub's 1 MB limit it is not, and the form is read: the login is refused.
    assert answer.startswith(b"HTTP/1.1 401") or answer.startswith(b"HTTP/1.1 422"), answer[:200]
