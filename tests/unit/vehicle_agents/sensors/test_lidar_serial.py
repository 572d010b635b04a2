"""The agent's serial path (pyserial on a real tty) with a sensor on the other end of a
pseudo-terminal: the simulator's wire bytes and command answers, as a USB serial adapter
would carry them. The agent opens the port at the model's baud rate, starts the sensor
with its commands, reads turns, and stops it on the way out."""

from __future__ import annotations

import asyncio
import contextlib
import os
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager

import pytest

from simulator.outputs.lidar import wire_format
from simulator.sensors.lidar import Lidar, LidarSpec, Pose
from simulator.wire.formats import Reply, Start, Stop
from simulator.world.obstacles import default_scene
from vehicle_agents.sensors.serial_lidar import SerialLidarSource
from vehicle_agents.sensors.turn import Turn


@contextmanager
def sensor_on_pty(wire: str) -> Iterator[tuple[str, list[str], threading.Event]]:
    """A simulated sensor on a pty's master side; yields the slave's path, the log of
    what it was told (start, stop) and an event set when it is stopped after a start."""
    master, slave = os.openpty()
    path = os.ttyname(slave)
    fmt = wire_format(wire)
    commands = fmt.commands()
    told: list[str] = []
    mode: list[str | None] = [fmt.streams]
    done = threading.Event()
    stopped = threading.Event()

    def run() -> None:
        lidar = Lidar(default_scene(), LidarSpec(), seed=1)
        encoders = {}
        os.set_blocking(master, False)
        started = time.monotonic()
        lidar.advance(Pose(0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0))
        while not done.is_set():
            try:
                data = os.read(master, 4096)
            except BlockingIOError:
                data = b""
            except OSError:
                return
            for action in commands.feed(data):
                if isinstance(action, Start):
                    told.append("start")
                    os.write(master, action.reply)
                    mode[0] = action.mode
                elif isinstance(action, Stop):
                    told.append("stop")
                    mode[0] = fmt.streams
                    if "start" in told:
                        stopped.set()
                elif isinstance(action, Reply):
                    os.write(master, action.data)
            beams = lidar.advance(Pose(time.monotonic() - started, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0))
            current = mode[0]
            if beams is not None and current is not None:
                encoder = encoders.setdefault(current, fmt.encoders[current](720))
                with contextlib.suppress(BlockingIOError):  # the reader is behind: bytes
                    os.write(master, encoder.encode(beams, 10.0))  # lost, as on a UART
            done.wait(0.02)

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    try:
        yield path, told, stopped
    finally:
        done.set()
        thread.join(2)
        os.close(slave)
        os.close(master)


async def _turns(
    path: str, model: str, scan_mode: int, count: int
) -> tuple[list[Turn], SerialLidarSource]:
    source = SerialLidarSource(path, model=model, scan_mode=scan_mode)
    turns: list[Turn] = []
    async with asyncio.timeout(20):
        async for turn in source.turns():
            turns.append(turn)
            if len(turns) >= count:
                break
    return turns, source


@pytest.mark.parametrize(
    ("wire", "model", "scan_mode"),
    [("rplidar-express", "rplidar-a2", 1), ("ydlidar-x4", "ydlidar-x4", 0), ("ld06", "stl27l", 0)],
)
def test_a_sensor_on_a_serial_port_is_started_read_and_stopped(
    wire: str, model: str, scan_mode: int
) -> None:
    with sensor_on_pty(wire) as (path, told, stopped):
        turns, source = asyncio.run(_turns(path, model, scan_mode, 3))
        assert min(sum(1 for r in t.ranges if r) for t in turns[1:]) > 300
        assert source.baud == {"rplidar-a2": 115200, "ydlidar-x4": 128000, "stl27l": 921600}[model]
        assert source.stats["points"] > 1000
        if wire != "ld06":
            assert source.parser.health is not None
            assert source.parser.health.status == 0
            # stopped before the start (a scan left running), started, stopped at the end
            assert stopped.wait(5)
            assert told[:2] == ["stop", "start"]
            assert told[-1] == "stop"
