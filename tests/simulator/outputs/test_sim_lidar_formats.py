"""The simulator's LIDAR in every wire format, read by the agent's parser for the model
`gcs demo --lidar` pairs with it: through the encoder (angles to 0.01 degree, ranges to
1 mm, or to the format's own resolution), over TCP through the agent's real source
(commands, answers, turns), and by `gcs-agent lidar-probe`."""

from __future__ import annotations

import asyncio
from collections.abc import Iterator

import pytest

from gcs.demo_lidars import DEMO_LIDARS
from simulator.config import ListenAddress, SimulatorConfig
from simulator.outputs.lidar import wire_format
from simulator.sensors.lidar import Lidar, LidarSpec, Pose
from simulator.server import SimulatorServer
from simulator.world.obstacles import default_scene
from vehicle_agents.sensors.lidar.models import MODELS, make_parser
from vehicle_agents.sensors.lidar.probe import probe
from vehicle_agents.sensors.serial_lidar import SerialLidarSource
from vehicle_agents.sensors.turn import Turn

# formats whose decoder moves each sample by a range-dependent angle: the simulator puts
# in each sample the range of the beam that angle points at, found on the 0.5-degree grid
CORRECTED = {"ydlidar-x4", "rplidar-ultra"}


def _beams(seconds: float) -> Iterator[tuple[list[int], list[float], list[int], object]]:
    lidar = Lidar(default_scene(), LidarSpec(noise_sigma_m=0.0, dropout=0.0), seed=2)
    for i in range(round(seconds / 0.02) + 1):
        beams = lidar.advance(Pose(i * 0.02, 0.5, -0.5, 1.0, 0.0, 0.0, 0.2))
        if beams is not None:
            yield (
                beams.index.tolist(),
                beams.angle_deg.tolist(),
                [round(r * 1000) for r in beams.range_m.tolist()],
                beams,
            )


@pytest.mark.parametrize("name", sorted(DEMO_LIDARS))
def test_each_format_parses_back_to_the_beams(name: str) -> None:
    demo = DEMO_LIDARS[name]
    wire = wire_format(demo.wire)
    capsules = demo.scan_mode != 0
    mode = next(m for m in wire.encoders if (m != "standard") == capsules or m == "scan")
    encoder = wire.encoders[mode](720)
    parser = make_parser(MODELS[demo.model])
    if capsules:
        parser.feed(
            {
                "rplidar-express": b"\xa5\x5a\x54\x00\x00\x40\x82",
                "rplidar-dense": b"\xa5\x5a\x54\x00\x00\x40\x85",
                "rplidar-ultra": b"\xa5\x5a\x84\x00\x00\x40\x84",
            }[demo.wire]
        )
    truth: dict[int, int] = {}
    decoded: list[tuple[float, int]] = []
    for index, _, distances, beams in _beams(0.6):
        truth.update(zip(index, distances, strict=True))
        for packet in parser.feed(encoder.encode(beams, 10.0)):  # type: ignore[arg-type]
            decoded += zip(packet.angles_deg, packet.distances_mm, strict=True)
    assert len(decoded) > 3500  # 0.6 s of 7,200 samples/s, less the encoder's last packet
    assert parser.stats.drops == {}
    returns = [(a, d) for a, d in decoded if d]
    assert len(returns) > 0.5 * len(decoded)
    if demo.wire not in CORRECTED:
        for angle, distance in decoded:
            grid = round(angle * 2)
            assert abs(angle - grid / 2) <= 0.01
            assert distance == truth[grid % 720]
        return
    # the decoded angle (less or plus its correction) falls within a quarter degree of a
    # beam of that range: the grid's resolution (0.5 degree) is all the simulator has
    tolerance_mm = 0 if demo.wire == "ydlidar-x4" else 16  # ultra: its variable bit scale
    near = 0
    for angle, distance in returns:
        grid = round(angle * 2)
        candidates = [truth.get((grid + k) % 720, -1) for k in (-1, 0, 1)]
        near += any(abs(c - distance) <= tolerance_mm for c in candidates)
    assert near >= 0.97 * len(returns)


async def _turns_over_tcp(name: str, count: int) -> list[Turn]:
    demo = DEMO_LIDARS[name]
    server = SimulatorServer(
        SimulatorConfig(
            listen=ListenAddress("tcp", "127.0.0.1", 0),
            lidar=ListenAddress("tcp", "127.0.0.1", 0),
            lidar_format=demo.wire,
            speedup=5.0,
        )
    )
    await server.start()
    try:
        assert server.lidar_address is not None
        source = SerialLidarSource(
            f"tcp://127.0.0.1:{server.lidar_address.port}",
            model=demo.model,
            scan_mode=demo.scan_mode,
        )
        turns: list[Turn] = []
        async with asyncio.timeout(20):
            async for turn in source.turns():
                turns.append(turn)
                if len(turns) >= count:
                    break
        stats = source.parser.stats
        assert stats.drops == {}, stats.drops
        if MODELS[demo.model].family != "ldlidar":
            assert stats.responses >= 3  # information, health, the scan's descriptor
        if source.parser.health is not None:
            assert source.parser.health.status == 0
        return turns
    finally:
        await server.stop()


@pytest.mark.parametrize(
    "name", ["ydlidar-x4", "rplidar", "rplidar-express", "rplidar-ultra", "ld06"]
)
def test_the_agents_source_reads_each_family_from_the_simulator(name: str) -> None:
    turns = asyncio.run(_turns_over_tcp(name, 3))
    returns = [sum(1 for r in turn.ranges if r) for turn in turns[1:]]
    assert min(returns) > 300  # the default yard around home, at 0.5 degree


async def _probe(wire: str) -> object:
    server = SimulatorServer(
        SimulatorConfig(
            listen=ListenAddress("tcp", "127.0.0.1", 0),
            lidar=ListenAddress("tcp", "127.0.0.1", 0),
            lidar_format=wire,
            speedup=1.0,
        )
    )
    await server.start()
    try:
        assert server.lidar_address is not None
        return await asyncio.to_thread(probe, f"tcp://127.0.0.1:{server.lidar_address.port}")
    finally:
        await server.stop()


@pytest.mark.parametrize(
    ("wire", "family", "hint"),
    [
        ("rplidar", "rplidar", "rplidar-a1"),
        ("ydlidar", "ydlidar", "ydlidar-tmini-pro"),
        ("ydlidar-x4", "ydlidar", "ydlidar-x4"),
        ("ld06", "ldlidar", "ld06"),
    ],
)
def test_the_probe_names_the_family_and_shows_a_turn(wire: str, family: str, hint: str) -> None:
    from vehicle_agents.sensors.lidar.probe import ProbeResult, describe

    result = asyncio.run(_probe(wire))
    assert isinstance(result, ProbeResult)
    assert result.family == family
    assert result.model_hint.startswith(hint)
    assert 5000 < result.points_per_s < 9000  # 720 points at 10 Hz
    assert len(result.turn) == 720
    text = describe(result)
    assert "points per second" in text
    assert "first turn: 720 points" in text
    if family != "ldlidar":
        assert result.health is not None
        assert result.health.status == 0
