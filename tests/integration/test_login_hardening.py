"""Logins under attack: the throttle cannot lock a user out, password hashing is bounded
and kept off the live service's threads, and the first admin's name is configurable.

The in-process hub (uvicorn's defaults) believes ``X-Forwarded-For`` from 127.0.0.1, as
the hub does behind a proxy on the same host: that is how these tests, like the attack
in the security review, come "from" many addresses.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import socket
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest

from backend.app import create_app
from backend.auth.password_work import PasswordWork
from backend.errors import RateLimited
from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.support.api import access_token, api_client, raw_http_answer
from tests.support.hub_server import running_hub
from tests.support.waiting import poll_until

PASSWORD = "correct horse battery"


def _login(client: httpx.Client, username: str, password: str, address: str) -> httpx.Response:
    return client.post(
        "/api/v1/auth/login",
        json={"username": username, "password": password},
        headers={"X-Forwarded-For": address},
    )


@pytest.fixture
def operator(hub: str, admin_api: httpx.Client) -> str:
    created = admin_api.post(
        "/api/v1/users", json={"username": "operator", "password": PASSWORD, "role": "operator"}
    )
    assert created.status_code == 201, created.text
    return "operator"


def test_wrong_passwords_from_elsewhere_do_not_lock_a_user_out(hub: str, operator: str) -> None:
    with httpx.Client(base_url=hub, timeout=30) as client:
        for n in range(6):
            assert _login(client, operator, "not the password", f"203.0.113.{n}").status_code == 401
        fresh = _login(client, operator, PASSWORD, "198.51.100.7")
    assert fresh.status_code == 200, fresh.text
    assert fresh.json()["username"] == operator


def test_guessing_one_user_from_one_address_is_throttled(hub: str, operator: str) -> None:
    with httpx.Client(base_url=hub, timeout=30) as client:
        statuses = [
            _login(client, operator, "not the password", "203.0.113.9").status_code
            for _ in range(5)
        ]
        # Even the right password waits, from that address: it may be the guesser's.
        locked = _login(client, operator, PASSWORD, "203.0.113.9")
        elsewhere = _login(client, operator, PASSWORD, "203.0.113.10")
    assert statuses == [401] * 5
    assert locked.status_code == 429
    assert int(locked.headers["retry-after"]) >= 1
    assert elsewhere.status_code == 200


def test_guessing_many_users_from_one_address_is_throttled(tmp_path: Path) -> None:
    settings = hub_settings(tmp_path, login_attempts_per_address_per_minute=3)
    with running_hub(settings) as hub, httpx.Client(base_url=hub, timeout=30) as client:
        statuses = [
            _login(client, f"user{n}", "not the password", "203.0.113.20").status_code
            for n in range(4)
        ]
        other_address = _login(client, "admin", ADMIN_PASSWORD, "203.0.113.21")
    assert statuses == [401, 401, 401, 429]
    assert other_address.status_code == 200


def test_an_address_over_its_login_rate_is_refused_before_its_body_is_read(
    tmp_path: Path,
) -> None:
    """A login flood's refusals are answered from the headers: the form is never read
    (here it never comes, and the answer does not wait for it)."""
    settings = hub_settings(tmp_path, login_attempts_per_address_per_minute=2)
    with running_hub(settings) as hub, httpx.Client(base_url=hub, timeout=30) as client:
        for n in range(2):
            assert _login(client, f"user{n}", "wrong", "203.0.113.30").status_code == 401
        host, port = hub.removeprefix("http://").split(":")
        with socket.create_connection((host, int(port)), timeout=5) as raw:
            raw.sendall(
                b"POST /api/v1/auth/token HTTP/1.1\r\nHost: x\r\n"
                b"X-Forwarded-For: 203.0.113.30\r\n"
                b"Content-Type: application/x-www-form-urlencoded\r\n"
                b"Content-Length: 500\r\n\r\nusername="
            )
            answer = raw_http_answer(raw)  # within the 5 s timeout
    assert answer.startswith("HTTP/1.1 429"), answer
    assert "login attempts" in answer


def test_a_login_is_refused_from_its_headers_while_every_password_check_is_taken(
    tmp_path: Path,
) -> None:
    """With `password_hash_max_pending` checks under way, the next login is refused before
    its form is read (here it never comes): a login flood's refusals cost the event loop
    its headers, not the form's parsing and the whole route."""
    settings = hub_settings(tmp_path, password_hash_threads=1, password_hash_max_pending=1)
    app = create_app(settings)
    release = threading.Event()
    with running_hub(settings, app) as hub:
        passwords = app.state.hub.passwords
        # The one password check allowed, held (as a slow hash would hold it) until released.
        holder = threading.Thread(target=asyncio.run, args=(passwords.run(release.wait, 30),))
        holder.start()
        try:
            poll_until(lambda: _refuses(passwords), 10, "the password checks all taken")
            host, port = hub.removeprefix("http://").split(":")
            with socket.create_connection((host, int(port)), timeout=5) as raw:
                raw.sendall(
                    b"POST /api/v1/auth/login HTTP/1.1\r\nHost: x\r\n"
                    b"Content-Type: application/json\r\nContent-Length: 500\r\n\r\n{"
                )
                answer = raw_http_answer(raw)  # within the 5 s timeout
        finally:
            release.set()
            holder.join(10)
    assert answer.startswith("HTTP/1.1 429"), answer
    assert "retry-after:" in answer.lower()
    assert "password checks in progress" in answer
    assert "password_hash_max_pending" in answer


def _refuses(passwords: PasswordWork) -> bool:
    try:
        passwords.check_room()
    except RateLimited:
        return True
    return False


def test_the_first_admin_name_is_configurable(tmp_path: Path) -> None:
    with running_hub(hub_settings(tmp_path, admin_username="chief")) as hub:
        token = access_token(hub, "chief", ADMIN_PASSWORD)
        with api_client(hub, token) as api:
            users = api.get("/api/v1/users").json()
        default_name = httpx.post(
            f"{hub}/api/v1/auth/token", data={"username": "admin", "password": ADMIN_PASSWORD}
        )
    assert [(user["username"], user["role"]) for user in users] == [("chief", "admin")]
    assert default_name.status_code == 401


@pytest.fixture
def small_hashing_hub(tmp_path: Path) -> Iterator[str]:
    # The production cost: the flood is only a flood when each check costs what it does.
    settings = hub_settings(
        tmp_path,
        password_hash_threads=1,
        password_hash_max_pending=2,
        password_hash_cost="standard",
    )
    with running_hub(settings) as hub:
        yield hub


def test_a_login_flood_from_many_addresses_is_refused_fast_and_the_api_stays_up(
    small_hashing_hub: str,
) -> None:
    """The review's attack, scaled down: failed logins with distinct names and addresses
    (each under every rate limit) while a dashboard keeps reading the fleet."""
    hub = small_hashing_hub
    token = access_token(hub, "admin", ADMIN_PASSWORD)
    flood = 40

    def failed_login(n: int) -> httpx.Response:
        with httpx.Client(base_url=hub, timeout=60) as client:
            return _login(client, f"nobody{n}", "not the password", f"10.{n // 250}.{n % 250}.1")

    with (
        concurrent.futures.ThreadPoolExecutor(flood) as attackers,
        api_client(hub, token) as dashboard,
    ):
        attempts = [attackers.submit(failed_login, n) for n in range(flood)]
        latencies = []
        while not all(attempt.done() for attempt in attempts) or len(latencies) < 5:
            started = time.perf_counter()
            assert dashboard.get("/api/v1/vehicles").status_code == 200
            latencies.append(time.perf_counter() - started)
        answers = [attempt.result() for attempt in attempts]

    busy = [answer for answer in answers if answer.status_code == 429]
    assert busy, "no password check was refused: hashing is not bounded"
    assert all(answer.status_code in (401, 429) for answer in answers)
    assert "password checks in progress" in busy[0].json()["detail"]
    assert int(busy[0].headers["retry-after"]) >= 1
    # At most two hashes at a time (one running, one waiting) leave the API's own threads
    # free: no read waits behind the flood (here 0.7 s at worst, against 5.9 s when every
    # login hashed on the shared pool).
    assert max(latencies) < 3.0, sorted(latencies)[-5:]


@pytest.mark.parametrize("role", ["admin", "operator", "viewer"])
@pytest.mark.parametrize("weak", ["aaaaaaaa", "password", "aaaaaaaaaaaaaaaa", "password1234"])
def test_weak_passwords_are_refused_for_every_role(
    admin_api: httpx.Client, role: str, weak: str
) -> None:
    created = admin_api.post(
        "/api/v1/users", json={"username": "weakling", "password": weak, "role": role}
    )
    assert created.status_code == 422, created.text
    detail = created.json()["detail"][0]
    assert detail["loc"] == ["body", "password"]
    assert any(rule in detail["msg"] for rule in ("at least 12 characters", "easy to guess"))
    assert admin_api.get("/api/v1/users").json()[-1]["username"] != "weakling"


def test_a_weak_password_reset_is_refused(admin_api: httpx.Client, operator: str) -> None:
    reset = admin_api.patch(f"/api/v1/users/{operator}", json={"password": "password"})
    assert reset.status_code == 422
    assert reset.json()["detail"][0]["loc"] == ["body", "password"]
    strong = admin_api.patch(f"/api/v1/users/{operator}", json={"password": "vivid-otter-lamp-42"})
    assert strong.status_code == 200, strong.text
