"""A running formation in the 3D view: the slot lines from its leader and the
separation sphere round each member (backend/formation/scene_layer.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from backend.formation.active import ActiveFormation
from backend.formation.planner import FormationPlan
from backend.formation.route import LeaderRoute
from backend.formation.scene_layer import SPHERE_OPACITY, FormationLayer, formation_view
from backend.formation.schemas import FormationRequest
from backend.viz3d.colours import rgb, vehicle_colour
from backend.viz3d.frame import SceneFrame
from backend.viz3d.scene import FleetScene
from backend.viz3d.server import VizServer
from common.formation import LeaderState, Offset, OffsetFrame
from common.geodesy import GeoPoint, LocalFrame
from tests.support.scenes import HOME, _node, _under

TRUTH = LocalFrame(*HOME)


@pytest.fixture
def scene(viz: VizServer) -> FleetScene:
    return FleetScene(viz.viser, SceneFrame(GeoPoint(*HOME)), trail_s=30.0)


def _formation(leader_id: str | None) -> ActiveFormation:
    # The formation's own frame 50 m east and 30 m north of the scene's origin.
    plan_frame = LocalFrame(*TRUTH.to_geo(50.0, 30.0))
    plan = FormationPlan(
        leader_id=leader_id,
        frame=plan_frame,
        route=LeaderRoute([(0, 0, 15), (40, 0, 15)], speed_ms=2.0, pause_s=0.0),
        offsets={
            "f1": Offset(-3.0, 3.0, -1.0),  # behind and right of the leader's heading
            "f2": Offset(5.0, 0.0, 0.0, OffsetFrame.NORTH_EAST),  # 5 m north whatever
        },
        min_separation_m=2.0,
    )
    request = FormationRequest.model_construct()  # only stored; the layer reads the plan
    return ActiveFormation("formation-1", request, plan, 0.0, offsets=plan.offsets)


def test_a_formations_slot_lines_and_separation_spheres_follow_it_and_go_on_stop(
    viz: VizServer, scene: FleetScene
) -> None:
    homes = {"lead": HOME[2], "f1": HOME[2], "f2": HOME[2] + 2.0}
    positions = {
        "lead": np.array([70.0, 40.0, 15.0]),
        "f1": np.array([66.0, 38.0, 14.0]),
        "f2": np.array([70.0, 44.0, 17.0]),
    }
    formation = _formation("lead")
    # Leader 10 m north and 20 m east of the formation's origin, 15 m up, heading east.
    leader = LeaderState(10.0, 20.0, 15.0, 0.0, 2.0, 0.0, math.pi / 2, 0.0)
    view = formation_view(formation, leader, scene.frame, homes.get, positions.get)
    assert view is not None
    layer = FormationLayer(scene)
    layer.sync([view], [formation.id])

    links = _node(viz.viser, "/formations/formation-1/links")
    assert links is not None
    # Heading east, "behind and right" is west and south: 3 m each, 1 m down.
    np.testing.assert_allclose(
        links.points,
        [[(70.0, 40.0, 15.0), (67.0, 37.0, 14.0)], [(70.0, 40.0, 15.0), (70.0, 45.0, 17.0)]],
        atol=0.01,
    )
    colours = np.asarray(links.colors).reshape(2, 2, 3)
    assert [tuple(c) for c in colours[:, 0]] == [rgb(vehicle_colour(v)) for v in ("f1", "f2")]
    for member, here in positions.items():
        sphere = _node(viz.viser, f"/formations/formation-1/separation/{member}")
        assert sphere is not None
        np.testing.assert_allclose(sphere.position, here, atol=1e-6)
        assert sphere.radius == pytest.approx(1.0)  # min_separation_m / 2
        assert sphere.opacity == pytest.approx(SPHERE_OPACITY)
    assert "formations" in scene.layers_shown

    # The leader moves 4 m east; f1 moves too: the lines and its sphere follow.
    moved = LeaderState(10.0, 24.0, 15.0, 0.0, 2.0, 0.0, math.pi / 2, 1.0)
    positions["f1"] = np.array([69.0, 38.0, 14.0])
    view = formation_view(formation, moved, scene.frame, homes.get, positions.get)
    assert view is not None
    layer.sync([view], [formation.id])
    np.testing.assert_allclose(links.points[0], [(74.0, 40.0, 15.0), (71.0, 37.0, 14.0)], atol=0.01)
    np.testing.assert_allclose(
        _node(viz.viser, "/formations/formation-1/separation/f1").position, positions["f1"]
    )

    layer.sync([], [])  # stopped: no longer among the running
    assert _under(viz.viser, "/formations/formation-1") == []
    assert layer.formations == []


def test_a_virtual_leader_is_placed_above_the_first_followers_home(
    viz: VizServer, scene: FleetScene
) -> None:
    formation = _formation(None)
    leader = LeaderState(0.0, 0.0, 15.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    homes = {"f1": HOME[2] + 1.0, "f2": HOME[2]}
    view = formation_view(formation, leader, scene.frame, homes.get, {}.get)
    assert view is not None
    np.testing.assert_allclose(view.leader, (50.0, 30.0, 16.0), atol=0.01)
    assert view.members == {}  # no positions yet: no spheres
    assert set(view.targets) == {"f1", "f2"}
