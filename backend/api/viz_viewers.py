"""The 3D view follows the map's selection: the dashboard names the vehicle selected for
its own 3D viewer (``backend.viz3d.viewers`` says how the dashboard learns which viewer
is its own, and the secret that proves it)."""

from __future__ import annotations

import asyncio
from typing import Annotated

from fastapi import Path
from pydantic import BaseModel, Field

from backend.api.deps import RegistryDep, ViewersDep
from backend.api.security import SecuredRouter, requires
from backend.auth.policy import Permission
from backend.errors import Conflict
from protocol.messages import VehicleId

router = SecuredRouter(prefix="/viz/viewers", tags=["3d view"])


class ViewerSelection(BaseModel):
    secret: str = Field(min_length=1, max_length=64, description="What the viewer's page said")
    vehicle_id: VehicleId


class ViewerLooksAt(BaseModel):
    vehicle_id: str
    look_at: tuple[float, float, float] = Field(description="East, north, up in the view, m")


@router.post(
    "/{viewer_id}/selection",
    response_model=ViewerLooksAt,
    openapi_extra=requires(Permission.READ),
)
async def select_in_viewer(
    viewer_id: Annotated[int, Path(ge=0, le=2**31)],
    body: ViewerSelection,
    registry: RegistryDep,
    viewers: ViewersDep,
) -> ViewerLooksAt:
    """Turn this 3D viewer's camera to the vehicle, which it then follows. 404 for an
    unknown viewer or a wrong secret (one answer for both); 409 while the vehicle has no
    position in the view, or when the 3D view is off."""
    if viewers is None:
        raise Conflict("the 3D view is off (GCS_VIZ_ENABLED=false)")
    registry.get(body.vehicle_id)  # 404 for an unknown vehicle
    look_at = await asyncio.to_thread(viewers.select, viewer_id, body.secret, body.vehicle_id)
    return ViewerLooksAt(vehicle_id=body.vehicle_id, look_at=look_at)
