"""The camera's parts, built from the agent's settings and started in its task group."""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable

from protocol.photos import parse_camera_model
from vehicle_agents.camera.folder import FolderCamera
from vehicle_agents.camera.queue import MIB, PhotoQueue
from vehicle_agents.camera.sources import open_source
from vehicle_agents.camera.trigger import CameraTrigger
from vehicle_agents.camera.upload import PhotoUploader
from vehicle_agents.config import AgentSettings, hub_http_base
from vehicle_agents.fcu.link import FcuLink
from vehicle_agents.sensors.fcu_time import FcuClock, PoseHistory

log = logging.getLogger(__name__)

Emit = Callable[..., None]


def start_camera(
    settings: AgentSettings,
    link: FcuLink,
    vehicle_id: str,
    token: str,
    emit: Emit,
    tasks: asyncio.TaskGroup,
) -> tuple[CameraTrigger, PhotoUploader]:
    assert settings.camera is not None

    def notify(text: str, severity: int) -> None:
        emit("upload", text, severity)

    camera = parse_camera_model(settings.camera_model)
    source = open_source(settings.camera, camera, notify)
    queue = PhotoQueue(settings.photo_folder(), round(settings.photo_budget_mb * MIB), notify)
    poses = PoseHistory(FcuClock())
    link.listeners.append(poses.on_message)
    trigger = CameraTrigger(vehicle_id, source, poses, queue, notify)
    link.listeners.append(trigger.on_message)
    uploader = PhotoUploader(
        queue,
        hub_http_base(settings.hub),
        vehicle_id,
        token,
        notify,
        rate_bytes_per_s=settings.photo_upload_rate_mb * MIB,
        concurrency=settings.photo_upload_concurrency,
    )
    tasks.create_task(trigger.run())
    if isinstance(source, FolderCamera):
        tasks.create_task(source.run())
    tasks.create_task(uploader.run())
    log.info(
        "camera %s (%dx%d px), photos in %s",
        settings.camera,
        camera.image_width_px,
        camera.image_height_px,
        queue.directory,
    )
    return trigger, uploader
