"""The agent's plain HTTP requests to the hub (and the simulator's camera): onboard .tlogs
and photos go over HTTP, never the telemetry WebSocket.

urllib, from the standard library: the agent's dependencies stay small. Redirects are not
followed (urllib would resend a PUT or POST as a bodiless GET), and a non-2xx answer
raises `HttpError` with the start of the hub's reason; a network failure raises OSError.
"""

from __future__ import annotations

import time
import urllib.error
import urllib.parse
import urllib.request
from dataclasses import dataclass
from typing import IO, Any

ERROR_BODY_ROOM = 500  # bytes of a refusal's body kept for the operator's event


class TooLarge(Exception):
    """The answer is longer than the caller's bound."""


class HttpError(Exception):
    """The server answered with something other than 2xx."""

    def __init__(self, status: int, reason: str, body: str) -> None:
        super().__init__(f"HTTP {status} {reason}: {body}")
        self.status = status
        self.reason = reason
        self.body = body


@dataclass(frozen=True)
class Answer:
    status: int
    headers: dict[str, str]
    body: bytes


class _NoRedirects(urllib.request.HTTPRedirectHandler):
    """urllib would follow a 301/302/303 by resending the request as a bodiless GET."""

    def redirect_request(self, *args: Any, **kwargs: Any) -> None:
        return None


_opener = urllib.request.build_opener(_NoRedirects)


def send(
    method: str,
    url: str,
    *,
    token: str | None = None,
    body: bytes | IO[bytes] | None = None,
    headers: dict[str, str] | None = None,
    timeout_s: float = 60.0,
    max_bytes: int | None = None,
) -> Answer:
    """One request (blocking: call it from a thread); the 2xx answer, read whole.

    With ``max_bytes``, an answer longer than that raises `TooLarge` (its declared length
    before a byte is read, else as soon as it passes the bound), and ``timeout_s`` bounds
    the whole read as well as each wait: a server that trickles bytes cannot hold the
    caller longer."""
    if urllib.parse.urlsplit(url).scheme not in ("http", "https"):
        raise ValueError(f"not an http(s) URL: {url!r}")
    all_headers = dict(headers or {})
    if token is not None:
        all_headers["Authorization"] = f"Bearer {token}"
    request = urllib.request.Request(url, data=body, method=method, headers=all_headers)
    try:
        with _opener.open(request, timeout=timeout_s) as response:
            headers = dict(response.headers.items())
            if max_bytes is None:
                return Answer(response.status, headers, response.read())
            return Answer(response.status, headers, _read_bounded(response, max_bytes, timeout_s))
    except urllib.error.HTTPError as error:
        with error:
            text = error.read(ERROR_BODY_ROOM).decode("utf-8", errors="replace")
        raise HttpError(error.code, str(error.reason), text) from None


READ_CHUNK = 64 * 1024


def _read_bounded(response: Any, max_bytes: int, timeout_s: float) -> bytes:
    declared = response.headers.get("Content-Length")
    if declared is not None and declared.isdigit() and int(declared) > max_bytes:
        raise TooLarge(f"{declared} bytes, more than the {max_bytes} allowed")
    deadline = time.monotonic() + timeout_s
    body = bytearray()
    while chunk := response.read(READ_CHUNK):
        body += chunk
        if len(body) > max_bytes:
            raise TooLarge(f"more than the {max_bytes} bytes allowed")
        if time.monotonic() > deadline:
            raise TimeoutError(f"the answer took longer than {timeout_s:g} s to arrive")
    return bytes(body)
