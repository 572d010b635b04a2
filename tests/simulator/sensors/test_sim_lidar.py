"""The simulator's world and its 2-D LIDAR: geometry, noise, skew, scene files, and the
YDLIDAR bytes it serves over TCP (parsed by the agent's own driver)."""

from __future__ import annotations

import asyncio
import json
import math
from pathlib import Path

import numpy as np
import pytest

from simulator import ListenAddress, SimulatorConfig, SimulatorServer
from simulator.sensors.lidar import Lidar, LidarSpec, Pose
from simulator.wire.ydlidar import encode_beams, health
from simulator.world.obstacles import Cylinder, World, box, load_scene, wall
from vehicle_agents.sensors.lidar.ydlidar import GET_HEALTH, START_SCAN, YdlidarParser
from vehicle_agents.sensors.turn import Turn
from vehicle_agents.sensors.turn_assembly import TurnAssembler

EXACT = LidarSpec(noise_sigma_m=0.0, dropout=0.0)


def _turns(
    world: World, poses: list[Pose], spec: LidarSpec = EXACT
) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    lidar = Lidar(world, spec, seed=3)
    out = []
    for pose in poses:
        beams = lidar.advance(pose)
        if beams is not None:
            out.append((beams.angle_deg, beams.range_m, beams.time_s))
    return out


def test_ray_cast_meets_each_kind_of_obstacle_at_its_surface() -> None:
    world = World(
        [
            box((5.0, 0.0), (2.0, 2.0)),
            Cylinder((0.0, 3.0), 0.5),
            wall((-4.0, -5.0), (4.0, -5.0), thickness=0.2),
        ]
    )
    origins = np.tile([0.0, 0.0, 2.0], (3, 1))
    directions = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0]])
    assert world.cast(origins, directions, 12.0) == pytest.approx([4.0, 2.5, 4.9])
    # above the wall's top (6 m) the ray passes; tilted down it meets the ground
    high = np.array([[0.0, 0.0, 7.0]])
    assert math.isinf(world.cast(high, np.array([[0.0, -1.0, 0.0]]), 12.0)[0])
    down = np.array([[-math.sqrt(0.5), 0.0, -math.sqrt(0.5)]])
    assert world.cast(high, down, 12.0)[0] == pytest.approx(7.0 * math.sqrt(2.0))


def test_a_hovering_lidar_sees_the_surfaces_with_the_configured_noise() -> None:
    world = World([Cylinder((0.0, 0.0), 6.0, z_max=10.0)])  # standing inside a round room
    spec = LidarSpec(noise_sigma_m=0.02, dropout=0.05)
    poses = [Pose(i * 0.02, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0) for i in range(60)]
    ranges = np.concatenate([r for _, r, _ in _turns(world, poses, spec)])
    hits = ranges[ranges > 0]
    assert abs(hits.mean() - 6.0) < 0.005
    assert 0.015 < hits.std() < 0.025
    assert 0.02 < 1.0 - len(hits) / len(ranges) < 0.09  # dropouts
    assert len(ranges) == pytest.approx(59 * 0.02 * 7200, abs=2)  # 720 beams x 10 Hz


def test_a_moving_drone_gets_a_skewed_scan() -> None:
    world = World([wall((-20.0, 5.0), (20.0, 5.0), thickness=0.2, z_max=10.0)])
    # flying north at 3 m/s toward the wall: the same bearing measured later is shorter
    poses = [Pose(i * 0.02, 0.0, 3.0 * i * 0.02, 2.0, 0.0, 0.0, 0.0) for i in range(8)]
    angles, ranges, times = (np.concatenate(x) for x in zip(*_turns(world, poses), strict=True))
    ahead = angles == 0.0
    assert ranges[ahead][0] == pytest.approx(4.9 - 3.0 * times[ahead][0], abs=1e-6)
    # beams 1 degree apart either side of north were taken ~0.1 s apart in the turn
    first, last = np.flatnonzero(angles == 0.5)[0], np.flatnonzero(angles == 359.5)[0]
    assert times[last] - times[first] == pytest.approx(0.1 * 718 / 720)
    slant = math.cos(math.radians(0.5))
    assert ranges[first] * slant - ranges[last] * slant == pytest.approx(
        3.0 * (times[last] - times[first]), abs=1e-4
    )


def test_scene_files_load_and_bad_ones_name_the_obstacle(tmp_path: Path) -> None:
    scene = tmp_path / "yard.json"
    scene.write_text(
        json.dumps(
            {
                "obstacles": [
                    {"kind": "box", "center": [10, 5], "size": [4, 2], "yaw_deg": 30, "height": 6},
                    {"kind": "cylinder", "center": [-8, 3], "radius": 0.5},
                    {"kind": "wall", "start": [-15, -10], "end": [15, -10]},
                    {
                        "kind": "polygon",
                        "points": [[0, 12], [6, 14], [3, 18]],
                        "z_min": 1,
                        "height": 4,
                    },
                ]
            }
        )
    )
    world = load_scene(scene)
    assert len(world.obstacles) == 4
    assert world.distance_to_surface(np.array([[-8.0, 3.5]]))[0] == pytest.approx(0.0)
    scene.write_text(
        json.dumps({"obstacles": [{"kind": "cylinder", "center": [0, 0]}, {"kind": "cone"}]})
    )
    with pytest.raises(ValueError, match="obstacle 0: a cylinder's radius must be > 0"):
        load_scene(scene)


def test_the_wire_bytes_parse_back_to_the_beams() -> None:
    world = World([Cylinder((0.0, 0.0), 6.0, z_max=10.0)])
    lidar = Lidar(world, EXACT)
    parser, assembler = YdlidarParser(), TurnAssembler()
    turns = []
    for i in range(40):
        beams = lidar.advance(Pose(i * 0.02, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0))
        if beams is not None:
            for packet in parser.feed(encode_beams(beams, 10.0)):
                turn = assembler.add(packet, i * 0.02)
                if turn is not None:
                    turns.append(turn)
    assert parser.stats.drops["bad_checksum"] == parser.stats.skipped_bytes == 0
    assert len(turns) == 7  # 0.78 s: the eighth turn is not finished
    assert set(turns[-1].ranges) == {6000}
    assert turns[-1].start == pytest.approx(0.6, abs=0.021)


def test_the_simulator_serves_its_lidar_bytes_over_tcp() -> None:
    asyncio.run(_serve_and_parse())


async def _serve_and_parse() -> None:
    config = SimulatorConfig(
        listen=ListenAddress("tcp", "127.0.0.1", 0),
        lidar=ListenAddress("tcp", "127.0.0.1", 0),
        speedup=5.0,
    )
    server = SimulatorServer(config)
    await server.start()
    try:
        assert server.lidar_address is not None
        reader, writer = await asyncio.open_connection("127.0.0.1", server.lidar_address.port)
        # Idle until started, as the sensor is: the health answer is the first byte back.
        writer.write(GET_HEALTH)
        async with asyncio.timeout(10):
            assert await reader.readexactly(10) == health()
        writer.write(START_SCAN)
        parser, assembler = YdlidarParser(), TurnAssembler()
        turns: list[Turn] = []
        async with asyncio.timeout(10):
            while len(turns) < 3:
                for packet in parser.feed(await reader.read(4096)):
                    turn = assembler.add(packet, asyncio.get_running_loop().time())
                    if turn is not None:
                        turns.append(turn)
        writer.close()
        assert parser.stats.drops["bad_checksum"] == parser.stats.skipped_bytes == 0
        assert parser.stats.responses == 1  # the start command's answer, then packets
        assert sum(1 for r in turns[-1].ranges if r) > 300  # the default yard around home
    finally:
        await server.stop()
