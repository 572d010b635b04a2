"""The cameras a simulator runs beside its autopilot: the photos over HTTP
(``--camera``), a MAVLink camera component (``--camera-component``) and a camera that
fills a folder (``--camera-folder``). Each is told of a shot the autopilot takes.

numpy and OpenCV are imported only by a simulator that renders photos.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Callable
from typing import TYPE_CHECKING

from simulator.config import SimulatorConfig
from simulator.mavlink.message_context import MavMessage
from simulator.vehicle import PhotoTaken

if TYPE_CHECKING:
    from simulator.outputs.cameras import CameraComponent, FolderCamera
    from simulator.outputs.photos import PhotoServer

log = logging.getLogger(__name__)

Broadcast = Callable[[MavMessage, int], None]  # a message to every peer, from a component


class CameraOutputs:
    """The configured cameras, started with the simulator and told of every shot."""

    def __init__(self, config: SimulatorConfig, broadcast: Broadcast) -> None:
        self.config = config
        self._broadcast = broadcast
        self.photos: PhotoServer | None = None
        self.camera_component: CameraComponent | None = None
        self.camera_folder: FolderCamera | None = None
        self._renderer: Callable[..., bytes] | None = None
        self._next_camera_heartbeat = 0.0
        self._boot_epoch_s = 0.0  # the autopilot's boot on the wall clock: poses' times
        # Shots for the camera folder, written one after another (a camera's card
        # fills in order) by one task.
        self._folder_shots: asyncio.Queue[PhotoTaken] = asyncio.Queue()
        self._folder_writer: asyncio.Task[None] | None = None

    async def start(self, boot_epoch_s: float) -> None:
        self._boot_epoch_s = boot_epoch_s
        if self.config.camera is None and self.config.camera_folder is None:
            return
        from simulator.outputs.photos import PhotoServer, nadir_renderer

        ground = self.config.ground or self.config.home
        render = await asyncio.to_thread(nadir_renderer, ground)  # the texture: a second
        self._renderer = render
        if self.config.camera is not None:
            self.photos = PhotoServer(self.config.camera, render, boot_epoch_s)
            photos_at = await self.photos.start()
            if self.config.camera_component:
                from simulator.outputs.cameras import CameraComponent

                assert self.config.camera_model is not None  # SimulatorConfig checks
                self.camera_component = CameraComponent(photos_at, self.config.camera_model)
        if self.config.camera_folder is not None:
            from simulator.outputs.cameras import FolderCamera

            assert self.config.camera_model is not None
            self.camera_folder = FolderCamera(self.config.camera_folder, self.config.camera_model)
            self._folder_writer = asyncio.create_task(
                self._write_to_folder(), name="simulator-camera-folder"
            )

    async def stop(self) -> None:
        if self.photos is not None:
            await self.photos.stop()
        if self._folder_writer is not None:
            self._folder_writer.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._folder_writer
            self._folder_writer = None

    def tick(self, wall: float) -> None:
        """The camera component's heartbeat, in wall time (what the agent's link
        timeouts measure)."""
        if self.camera_component is not None and wall >= self._next_camera_heartbeat:
            from simulator.outputs.cameras import CAMERA_COMPONENT_ID

            self._next_camera_heartbeat = wall + 1.0  # a MAVLink component's 1 Hz
            self._broadcast(self.camera_component.heartbeat(), CAMERA_COMPONENT_ID)

    def serve_photo(self, photo: PhotoTaken) -> None:
        """The photo server keeps the shot: called before the autopilot's feedback, which
        the agent fetches on."""
        if self.photos is not None:
            self.photos.taken(photo)

    def camera_shot(self, photo: PhotoTaken) -> None:
        """The shot as the camera itself tells of it, where it is a component or fills a
        folder."""
        if self.camera_component is not None:
            from simulator.outputs.cameras import CAMERA_COMPONENT_ID
            from simulator.outputs.photos import pose_of

            pose = pose_of(photo, self._boot_epoch_s)
            self._broadcast(
                self.camera_component.image_captured(photo, pose, self._boot_epoch_s),
                CAMERA_COMPONENT_ID,
            )
        if self.camera_folder is not None:
            self._folder_shots.put_nowait(photo)

    def restart(self, boot_epoch_s: float) -> None:
        """The flight controller rebooted: its boot clock starts again."""
        self._boot_epoch_s = boot_epoch_s
        if self.photos is not None:
            self.photos.restart(boot_epoch_s)
        if self.camera_component is not None:
            self.camera_component.restart()

    async def _write_to_folder(self) -> None:
        """Render each shot and write it to the camera's folder, off the event loop: the
        file lands a moment after the autopilot's message, as a real camera's does."""
        from simulator.outputs.photos import pose_of

        assert self.camera_folder is not None
        assert self._renderer is not None
        folder = self.camera_folder
        number = 0
        while True:
            photo = await self._folder_shots.get()
            number += 1  # the card's own count: DSC00001 first
            pose = pose_of(photo, self._boot_epoch_s)
            try:
                jpeg = await asyncio.to_thread(self._renderer, pose, folder.camera)
                await asyncio.to_thread(folder.write, number, jpeg)
            except (ValueError, OSError) as error:
                log.warning("camera folder: shot %d not written: %s", photo.index, error)
