"""A store that stops answering, and the wait for it to answer again."""

from __future__ import annotations

import json
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from protocol.messages import CommandOutcome, CommandResult, encode
from tests.support.agents import ScriptedAgent


@contextmanager
def answering(agent: ScriptedAgent) -> Iterator[list[dict[str, Any]]]:
    """Accept the next command as a flight controller would, from a helper thread;
    yields the commands received, filled in on the way out."""
    received: list[dict[str, Any]] = []

    def answer() -> None:
        request = json.loads(agent.recv(timeout=10))
        received.append(request["command"])
        outcome = CommandOutcome(status="accepted", result="MAV_RESULT_ACCEPTED", message="ok")
        agent.send(encode(CommandResult(request_id=request["request_id"], outcome=outcome)))

    worker = threading.Thread(target=answer, daemon=True)
    worker.start()
    yield received
    worker.join(10)
