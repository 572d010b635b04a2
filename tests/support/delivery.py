"""The agent protocol's acknowledgements and resend requests, read frame by frame."""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from typing import Any

from tests.support.agents import ScriptedAgent


def _next(socket: ScriptedAgent, wanted: Callable[[dict[str, Any]], bool]) -> dict[str, Any]:
    """The first frame from the hub that matches, within a few seconds."""
    deadline = time.monotonic() + 10
    while True:
        frame = json.loads(socket.recv(timeout=max(0.1, deadline - time.monotonic())))
        if wanted(frame):
            return frame


def _acked(kind: str, seq: int) -> Callable[[dict[str, Any]], bool]:
    return lambda frame: frame["type"] == "ack" and frame.get(f"{kind}_seq") == seq
