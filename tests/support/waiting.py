"""Polling for state that announces nothing; waiting on an event is better where there is one."""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable
from typing import TypeVar

T = TypeVar("T")


def poll_until(
    condition: Callable[[], T], timeout_s: float, what: str, *, every_s: float = 0.2
) -> T:
    """``condition()``'s first true value, for state that announces nothing (a file, a
    table, the hub's store behind its batching writer)."""
    deadline = time.monotonic() + timeout_s
    while not (value := condition()):
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout_s:.0f} s waiting for {what}")
        time.sleep(every_s)  # polling: there is no event to wait on
    return value


async def poll_until_async(
    condition: Callable[[], T], timeout_s: float, what: str, *, every_s: float = 0.05
) -> T:
    """`poll_until` inside an event loop: sleeps without blocking the loop, so the tasks
    under test run between looks."""
    deadline = time.monotonic() + timeout_s
    while not (value := condition()):
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout_s:g} s waiting for {what}")
        await asyncio.sleep(every_s)  # polling: there is no event to wait on
    return value
