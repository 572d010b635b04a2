"""The hub's long-running work: its services' loops and its own housekeeping."""

from __future__ import annotations

import asyncio
import logging
import time

from sqlalchemy.exc import SQLAlchemyError

from backend.hub.services import Hub
from backend.realtime.bus import Topic
from backend.storage.retention import RetentionPolicy
from backend.viz3d.mirror import SceneMirror
from protocol.messages import (
    MapLayer,
)

log = logging.getLogger(__name__)

POINT_MAP_PUBLISH_S = 2.0


async def run_hub(hub: Hub) -> None:
    """The hub's long-running work; cancel it to stop (the writer flushes first)."""
    try:
        async with asyncio.TaskGroup() as tasks:
            tasks.create_task(hub.writer.run())
            tasks.create_task(hub.fanout.run())
            tasks.create_task(hub.scans.run())
            tasks.create_task(_watch_obstacles(hub))
            tasks.create_task(_publish_point_map(hub))
            tasks.create_task(_apply_retention(hub))
            tasks.create_task(_drain_spool(hub))
            tasks.create_task(_flush_denials(hub))
            tasks.create_task(hub.surveys.run())
            tasks.create_task(hub.mosaic.run())
            tasks.create_task(hub.photos.run())
            tasks.create_task(hub.manual_control.watch_expiry())
            for work in hub.background:
                tasks.create_task(work())
            if hub.fleet_link is not None:
                tasks.create_task(hub.fleet_link.run())
            if hub.scene is not None:
                mirror = SceneMirror(
                    hub.scene,
                    hub.bus,
                    hub.registry,
                    hub.settings.viz_update_interval_s,
                    surveys=hub.surveys,
                    mosaics=hub.mosaic,
                    mosaic_surveys=lambda: [run.id for run in hub.surveys.known()],
                    layers=hub.scene_layers,
                )
                tasks.create_task(mirror.run())
    finally:
        # The counts of refusals not yet written, before the store closes.
        await hub.record_all(hub.denials.closed(everything=True))
        if hub.fleet_link is not None:
            await hub.fleet_link.close()
        await asyncio.to_thread(hub.mosaic.close)  # the tiles in memory to disk
        if hub.viz_http is not None:
            await hub.viz_http.aclose()
        if hub.viz is not None:
            await asyncio.to_thread(hub.viz.stop)
        hub.passwords.close()
        hub.tiles.close()
        hub.engine.dispose()


async def _apply_retention(hub: Hub) -> None:
    policy = hub.settings.retention_policy()
    if policy == RetentionPolicy():
        return
    while True:
        try:
            removed = await asyncio.to_thread(hub.logbook.apply_retention, policy, time.time())
        except SQLAlchemyError as error:
            # Retention can wait for the next round; it must never stop the hub.
            log.warning("retention skipped: %s", error)
        else:
            if any(removed.values()):
                log.info("retention removed %s", removed)
        await asyncio.sleep(hub.settings.retention_interval_s)


async def _watch_obstacles(hub: Hub) -> None:
    """Obstacles found in the point map, or gone from it, as events."""
    while True:
        await asyncio.sleep(hub.settings.scan_obstacle_interval_s)
        try:
            await hub.refresh_obstacles()
        except Exception:
            # A map that cannot be clustered this time must never stop the hub.
            log.exception("obstacle extraction failed")


async def _publish_point_map(hub: Hub) -> None:
    """The point map to the feeds that subscribed to it, when it has changed, at most
    every POINT_MAP_PUBLISH_S: it changes little from one second to the next, and its
    newest voxels are the heaviest message on the feed."""
    published = -1
    while True:
        await asyncio.sleep(POINT_MAP_PUBLISH_S)
        version = hub.scans.map_version
        if version == published or not hub.bus.subscribers(Topic.MAP):
            continue
        published = version
        points: tuple[MapLayer] = ("points",)
        [update] = await hub.map_now(points)
        await hub.bus.publish(Topic.MAP, update.type, update)


async def _drain_spool(hub: Hub) -> None:
    """Store the rows spooled during a database outage as soon as it is over."""
    while True:
        if hub.spool.pending:
            try:
                await asyncio.to_thread(hub.spool.drain)
            except OSError as error:
                log.error("spooled rows could not be read or rewritten: %s", error)
        # Polling: an outage's end announces nothing.
        await asyncio.sleep(hub.settings.spool_retry_s)


async def _flush_denials(hub: Hub) -> None:
    """Write the counts of refusal windows that have closed."""
    while True:
        await asyncio.sleep(hub.denials.interval_s)
        await hub.record_all(hub.denials.closed())
