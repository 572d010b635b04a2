"""The agent's health, for a supervisor that cannot ask the running process: a container
engine's health check (`gcs-agent --health`) or a monitoring script.

The running agent rewrites a small JSON file every few seconds with whether it hears its
flight controller and holds its link to the hub; ``check`` reads it. A file that stopped
changing means an agent that is stuck or gone, whatever the file last said.
"""

from __future__ import annotations

import asyncio
import json
import os
import time
from collections.abc import Callable
from pathlib import Path

WRITE_INTERVAL_S = 5.0
# Three missed rewrites: a loop too busy for that long is as bad as a dead one.
STALE_AFTER_S = 3 * WRITE_INTERVAL_S


class HealthFile:
    """Rewrites ``path`` every ``interval_s`` with the two links' states."""

    def __init__(
        self,
        path: Path,
        fcu_up: Callable[[], bool],
        hub_up: Callable[[], bool],
        interval_s: float = WRITE_INTERVAL_S,
    ) -> None:
        self.path = path
        self.fcu_up = fcu_up
        self.hub_up = hub_up
        self.interval_s = interval_s

    def write(self) -> None:
        state = {"written_at": time.time(), "fcu": self.fcu_up(), "hub": self.hub_up()}
        # Written whole, then renamed over the old one: a reader never sees half a file.
        partial = self.path.with_name(self.path.name + ".partial")
        partial.write_text(json.dumps(state))
        os.replace(partial, self.path)

    async def run(self) -> None:
        self.path.parent.mkdir(parents=True, exist_ok=True)
        try:
            while True:
                await asyncio.to_thread(self.write)
                await asyncio.sleep(self.interval_s)
        finally:
            # A stopped agent leaves no file saying it was healthy.
            self.path.unlink(missing_ok=True)


def check(path: Path, now: float | None = None) -> str | None:
    """None when the agent is healthy, else what is wrong, in words."""
    try:
        state = json.loads(path.read_text())
        written_at = float(state["written_at"])
        fcu, hub = bool(state["fcu"]), bool(state["hub"])
    except FileNotFoundError:
        return (
            f"{path} does not exist: the agent is not running, or has not yet heard its "
            "flight controller"
        )
    except (OSError, ValueError, KeyError, TypeError) as error:
        return f"{path} is unreadable: {error}"
    age = (time.time() if now is None else now) - written_at
    if age > STALE_AFTER_S:
        return f"{path} was last written {age:.0f} s ago: the agent is stuck or stopped"
    down = [name for name, up in (("flight controller", fcu), ("hub", hub)) if not up]
    if down:
        return f"no link to the {' or the '.join(down)}"
    return None
