"""A 3D-view layer that fails is logged and started again; it never ends the hub's
other work (the mirror runs in the hub's task group)."""

from __future__ import annotations

import asyncio
import logging

import pytest

from backend.viz3d.mirror import contained


def test_a_failing_layer_is_restarted_and_its_neighbour_keeps_running(
    caplog: pytest.LogCaptureFixture,
) -> None:
    calls = 0
    neighbour_done = asyncio.Event()

    async def flaky() -> None:
        nonlocal calls
        calls += 1
        if calls < 3:
            raise ValueError("a bad tile")

    async def neighbour() -> None:
        await asyncio.sleep(0)
        neighbour_done.set()

    async def main() -> None:
        async with asyncio.TaskGroup() as tasks:
            tasks.create_task(contained("mosaic", flaky, restart_s=0.01))
            tasks.create_task(contained("vehicles", neighbour, restart_s=0.01))

    with caplog.at_level(logging.ERROR, logger="backend.viz3d.mirror"):
        asyncio.run(asyncio.wait_for(main(), 10))
    assert calls == 3
    assert neighbour_done.is_set()
    failures = [r for r in caplog.records if "the mosaic layer failed" in r.getMessage()]
    assert len(failures) == 2
    assert failures[0].exc_info is not None


def test_cancelling_a_layer_ends_it_without_a_restart() -> None:
    started = asyncio.Event()
    runs = 0

    async def forever() -> None:
        nonlocal runs
        runs += 1
        started.set()
        await asyncio.Event().wait()

    async def main() -> None:
        task = asyncio.create_task(contained("scans", forever, restart_s=0.01))
        await asyncio.wait_for(started.wait(), 5)
        task.cancel()
        with pytest.raises(asyncio.CancelledError):
            await task

    asyncio.run(main())
    assert runs == 1
