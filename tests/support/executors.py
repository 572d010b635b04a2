"""The agent's command executor against the simulator in this process."""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Awaitable, Callable
from typing import TypeVar

from tests.support.mavlink_peer import ScriptedFlightController
from vehicle_agents.control.executor import CommandExecutor
from vehicle_agents.fcu.commands import CommandTimeouts
from vehicle_agents.fcu.link import FcuLink

# Short enough that a case takes a second or two, long enough for a loaded machine.
TIMEOUTS = CommandTimeouts(ack_s=0.5, attempts=3, in_progress_s=1.5)


T = TypeVar("T")


def with_executor(
    fcu: ScriptedFlightController, body: Callable[[CommandExecutor], Awaitable[T]]
) -> T:
    """Run ``body`` with an executor on a live FcuLink to ``fcu``."""

    async def run() -> T:
        link = FcuLink(f"tcp:127.0.0.1:{fcu.port}")
        running = asyncio.create_task(link.run())
        try:
            await asyncio.wait_for(link.wait_identified(), 10)
            return await body(CommandExecutor(link, TIMEOUTS))
        finally:
            running.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await running

    return asyncio.run(run())
