"""The 3D view's survey, formation and mosaic layers, driven with real surveys, formation
plans and tile stores and read back through the viser server's own scene API."""

from __future__ import annotations

import asyncio
import contextlib
import math
from pathlib import Path
from typing import Any, cast

import numpy as np
import pytest
import viser

from backend.auth.policy import Principal
from backend.imagery.mosaic.georef import TILE_PX, pixel_to_lonlat
from backend.imagery.mosaic.service import MosaicService
from backend.imagery.mosaic.store import TileStore
from backend.imagery.mosaic.viz_layer import GROUND_LIFT_M, MAX_TEXTURE_PX, MosaicLayer
from backend.realtime.bus import InProcessBus
from backend.settings import HubSettings
from backend.storage.database import make_engine, migrate
from backend.survey.flight.progress import new_run
from backend.survey.flight.run import DroneState, SurveyRun, SurveyState
from backend.survey.planning.schemas import SurveyRequest
from backend.survey.planning.survey import Fleet, plan_survey, summary
from backend.survey.repository import StoredSurvey, SurveyRepository
from backend.survey.service import SurveyService
from backend.survey.viz_layer import PlannedLanes, SurveyLanes
from backend.viz3d.colours import rgb, vehicle_colour
from backend.viz3d.frame import SceneFrame
from backend.viz3d.scene import FleetScene
from backend.viz3d.server import VizServer
from common.geodesy import GeoPoint, LocalFrame
from tests.support.survey_shapes import geojson_area
from tests.support.waiting import poll_until_async

HOME = (47.397742, 8.545594, 488.0)
TRUTH = LocalFrame(*HOME)


def _node(server: viser.ViserServer, name: str) -> Any:
    return server.scene._handle_from_node_name.get(name)


def _under(server: viser.ViserServer, root: str) -> list[str]:
    """The nodes at or under ``root``: viser's own parent frames included."""
    names = server.scene._handle_from_node_name
    return [name for name in names if name == root or name.startswith(root + "/")]


@pytest.fixture
def scene(viz: VizServer) -> FleetScene:
    return FleetScene(viz.viser, SceneFrame(GeoPoint(*HOME)), trail_s=30.0)


# -- survey lanes -----------------------------------------------------------------------


def _survey(drones: DroneState = DroneState.FLYING) -> SurveyRun:
    """A real plan over 300 x 200 m north-east of home, split between two drones, flown."""
    request = SurveyRequest.model_validate(
        {
            "area": geojson_area(TRUTH, [(40, 30), (340, 30), (340, 230), (40, 230)]),
            "camera": "dji_phantom4_pro",
            "gsd_cm": 2.0,
            "angle_deg": 0,
            "vehicle_ids": ["a", "b"],
        }
    )
    spots = {v: GeoPoint(*TRUTH.to_geo(east, 0.0), HOME[2]) for v, east in (("a", 0), ("b", 8))}
    fleet = [Fleet(v, spot, spot) for v, spot in spots.items()]
    run = new_run(request, summary(plan_survey(request, fleet)))
    run.state = SurveyState.FLYING
    for drone in run.drones:
        drone.state = drones
    return run


def test_a_flown_surveys_lanes_are_drawn_at_altitude_per_drone_and_go_on_abort(
    viz: VizServer, scene: FleetScene
) -> None:
    homes = {"a": HOME[2], "b": HOME[2] + 3.0}  # b's home 3 m higher: its lanes too
    layer = SurveyLanes(scene, homes.get)
    run = _survey()
    assert {len(d.lanes) for d in run.drones} != {0}
    layer.show(PlannedLanes.of(run))
    for drone in run.drones:
        node = _node(viz.viser, f"/survey_lanes/{run.id}/{drone.vehicle_id}")
        assert node is not None
        alt = homes[drone.vehicle_id] + run.altitude_m
        expected = [
            [TRUTH.to_enu(*lane.start, alt), TRUTH.to_enu(*lane.end, alt)] for lane in drone.lanes
        ]
        np.testing.assert_allclose(node.points, expected, atol=0.01)
        assert tuple(np.asarray(node.colors).reshape(-1, 3)[0]) == rgb(
            vehicle_colour(drone.vehicle_id)
        )
    assert "survey_lanes" in scene.layers_shown

    run.state = SurveyState.ABORTED
    layer.show(PlannedLanes.of(run))
    assert _under(viz.viser, f"/survey_lanes/{run.id}") == []
    assert layer.surveys == []


def test_a_planned_survey_is_not_drawn(viz: VizServer, scene: FleetScene) -> None:
    run = _survey()
    run.state = SurveyState.PLANNED
    SurveyLanes(scene, lambda _: HOME[2]).show(PlannedLanes.of(run))
    assert _node(viz.viser, f"/survey_lanes/{run.id}/a") is None
    assert "survey_lanes" not in scene.layers_shown


def test_the_lanes_follow_the_survey_service_from_a_resumed_survey_to_its_abort(
    viz: VizServer, scene: FleetScene, tmp_path: Path
) -> None:
    """The layer's own feed: the surveys a restarted hub resumes from its store, then the
    survey's messages on the bus (an abort)."""
    engine = make_engine(f"sqlite:///{tmp_path / 'hub.sqlite'}")
    migrate(engine)
    repository = SurveyRepository(engine)
    # Its drones still on the ground: the abort has nobody to send home, so the service
    # needs none of the hub's command path (hence no hub).
    run = _survey(drones=DroneState.ASSIGNED)
    repository.save(StoredSurvey(run.id, run.created, run.state, "op", run.model_dump_json()))
    settings = HubSettings(environment="development", admin_password="x" * 12)
    bus = InProcessBus()

    def lanes_of(vehicle_id: str) -> Any:
        return _node(viz.viser, f"/survey_lanes/{run.id}/{vehicle_id}")

    async def flight() -> None:
        surveys = SurveyService(cast(Any, None), bus, repository, settings)
        await surveys.load()
        layer = SurveyLanes(scene, lambda _: HOME[2])
        feed = asyncio.create_task(layer.follow(bus, surveys, interval_s=0.05))
        try:
            await poll_until_async(lambda: lanes_of("a") and lanes_of("b"), 5, "the lanes")
            await surveys.abort(run.id, Principal("op", "operator", frozenset()))
            await poll_until_async(lambda: not (lanes_of("a") or lanes_of("b")), 5, "no lanes")
        finally:
            feed.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await feed

    try:
        asyncio.run(flight())
    finally:
        engine.dispose()


# -- the mosaic --------------------------------------------------------------------------

# The tile under home at a survey's zoom, and so the mosaic's extent in tiles.
ZOOM = 19
_HOME_X = int((HOME[1] + 180) / 360 * 2**ZOOM)
_HOME_Y = int((1 - math.asinh(math.tan(math.radians(HOME[0]))) / math.pi) / 2 * 2**ZOOM)
BLUE_BGRA = np.array([255, 0, 0, 255], dtype=np.uint8)
GREY_BGRA = np.array([90, 90, 90, 255], dtype=np.uint8)


def _fill(store: TileStore, tiles: dict[int, tuple[int, int]]) -> None:
    """Per zoom, every tile of a ``columns`` x ``rows`` block from home's tile: grey but
    for the block's north-west tile, which is blue. One revision more, as a photo adds."""
    distances = np.zeros((TILE_PX, TILE_PX), dtype=np.float32)
    for zoom, (columns, rows) in tiles.items():
        shift = ZOOM - zoom
        x0, y0 = _HOME_X >> shift, _HOME_Y >> shift
        for x in range(x0, x0 + columns):
            for y in range(y0, y0 + rows):
                colour = BLUE_BGRA if (x, y) == (x0, y0) else GREY_BGRA
                store.write((zoom, x, y), np.tile(colour, (TILE_PX, TILE_PX, 1)), distances)
    store.revision += 1


def _mosaics(folder: Path, tiles: dict[int, tuple[int, int]], min_zoom: int) -> MosaicService:
    """The mosaic service over one survey's tiles on disk (``folder``/s1), as after a
    restart."""
    store = TileStore.open(folder / "s1")
    store.max_zoom, store.min_zoom = max(tiles), min_zoom
    _fill(store, tiles)
    store.flush()
    mosaics = MosaicService(folder, lambda _: asyncio.sleep(0, None))
    asyncio.run(mosaics.load())
    return mosaics


def _extent(zoom: int, columns: int, rows: int) -> tuple[np.ndarray, np.ndarray]:
    shift = ZOOM - zoom
    x0, y0 = (_HOME_X >> shift) * TILE_PX, (_HOME_Y >> shift) * TILE_PX
    west, north = pixel_to_lonlat(zoom, x0, y0)
    east, south = pixel_to_lonlat(zoom, x0 + columns * TILE_PX, y0 + rows * TILE_PX)
    south_west = np.array(TRUTH.to_enu(south, west, HOME[2]))
    north_east = np.array(TRUTH.to_enu(north, east, HOME[2]))
    return south_west, north_east


def test_a_mosaic_is_a_ground_plane_over_its_extent_redrawn_as_it_grows(
    viz: VizServer, scene: FleetScene, tmp_path: Path
) -> None:
    mosaics = _mosaics(tmp_path, {ZOOM: (2, 1), ZOOM - 1: (1, 1)}, min_zoom=ZOOM - 1)
    layer = MosaicLayer(scene)
    layer.refresh(mosaics, ["s1", "not-flown"])

    plane = _node(viz.viser, "/mosaic/s1")
    assert plane is not None
    south_west, north_east = _extent(ZOOM, 2, 1)  # the finest zoom: 2 x 1 tiles fit
    assert plane.render_width == pytest.approx(north_east[0] - south_west[0], abs=0.01)
    assert plane.render_height == pytest.approx(north_east[1] - south_west[1], abs=0.01)
    assert 2 * TILE_PX * 0.2 < plane.render_width < 2 * TILE_PX * 0.3  # ~0.23 m a pixel
    centre = (south_west + north_east) / 2 + (0, 0, GROUND_LIFT_M)
    np.testing.assert_allclose(plane.position, centre, atol=0.01)
    np.testing.assert_allclose(plane.wxyz, (0, 1, 0, 0))  # north up, west left
    assert plane.image.shape == (TILE_PX, 2 * TILE_PX, 4)
    assert tuple(plane.image[0, 0]) == (0, 0, 255, 255)  # the NW tile, BGRA made RGBA
    assert tuple(plane.image[-1, -1]) == (90, 90, 90, 255)
    assert "mosaic" in scene.layers_shown
    assert layer.mosaics == ["s1"]

    # Photos arrive: now 6 x 5 tiles at the finest zoom, too many for one texture; the
    # zoom below's 3 x 3 fit.
    survey = mosaics.survey("s1")
    with survey.lock:
        _fill(survey.store, {ZOOM: (6, 5), ZOOM - 1: (3, 3)})
    layer.refresh(mosaics, ["s1"])
    plane = _node(viz.viser, "/mosaic/s1")
    assert plane.image.shape == (3 * TILE_PX, 3 * TILE_PX, 4)
    south_west, north_east = _extent(ZOOM - 1, 3, 3)
    assert plane.render_width == pytest.approx(north_east[0] - south_west[0], abs=0.01)
    assert plane.render_height == pytest.approx(north_east[1] - south_west[1], abs=0.01)

    layer.refresh(mosaics, [])  # no longer among the surveys shown
    assert _under(viz.viser, "/mosaic/s1") == []


def test_a_mosaic_wider_than_every_zoom_allows_is_scaled_down(
    viz: VizServer, scene: FleetScene, tmp_path: Path
) -> None:
    mosaics = _mosaics(tmp_path, {ZOOM: (6, 1)}, min_zoom=ZOOM)
    MosaicLayer(scene).refresh(mosaics, ["s1"])
    plane = _node(viz.viser, "/mosaic/s1")
    assert plane.image.shape == (TILE_PX * MAX_TEXTURE_PX // (6 * TILE_PX), MAX_TEXTURE_PX, 4)
    south_west, north_east = _extent(ZOOM, 6, 1)
    assert plane.render_width == pytest.approx(north_east[0] - south_west[0], abs=0.01)
