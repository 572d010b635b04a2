"""The hub's REST API as an integration calls it: tokens, clients, commands, raw answers."""

from __future__ import annotations

import socket
from typing import Any

import httpx


def access_token(base_url: str, username: str, password: str) -> str:
    """A bearer token through the OAuth2 password flow, as an integration gets one."""
    response = httpx.post(
        f"{base_url}/api/v1/auth/token", data={"username": username, "password": password}
    )
    response.raise_for_status()
    token: str = response.json()["access_token"]
    return token


def api_client(base_url: str, token: str, timeout_s: float = 30) -> httpx.Client:
    return httpx.Client(
        base_url=base_url, timeout=timeout_s, headers={"Authorization": f"Bearer {token}"}
    )


def send_command(api: httpx.Client, vehicle: str, **command: Any) -> dict[str, Any]:
    """A command through the REST API, which must answer 200; returns its outcome."""
    response = api.post(f"/api/v1/vehicles/{vehicle}/commands", json=command)
    assert response.status_code == 200, response.text
    outcome: dict[str, Any] = response.json()["outcome"]
    return outcome


def raw_http_answer(sock: socket.socket) -> str:
    """One HTTP/1.1 answer read off a raw socket, headers and body by its Content-Length,
    without waiting for the connection to close (the server may still be reading)."""
    data = b""
    while b"\r\n\r\n" not in data:
        chunk = sock.recv(4096)
        if not chunk:
            break
        data += chunk
    head, _, body = data.partition(b"\r\n\r\n")
    length = next(
        (
            int(line.split(b":", 1)[1])
            for line in head.split(b"\r\n")
            if line.lower().startswith(b"content-length:")
        ),
        0,
    )
    while len(body) < length:
        chunk = sock.recv(4096)
        if not chunk:
            break
        body += chunk
    return (head + b"\r\n\r\n" + body).decode()
