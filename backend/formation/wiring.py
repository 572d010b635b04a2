"""The formation feature on a started hub: its service (over the hub's fleet, safety
gate, store and scans), its relay run with the hub's work, and its layer of the 3D view.
app.py calls ``attach`` once the hub has started, before it runs."""

from __future__ import annotations

from backend.formation.leader_scans import leader_scans
from backend.formation.scene_layer import formation_scene_layer
from backend.formation.service import FormationService
from backend.formation.store import FormationRepository
from backend.hub.services import Hub


async def attach(hub: Hub) -> FormationService:
    service = FormationService(
        hub.registry,
        hub.safety,
        repository=FormationRepository(hub.engine),
        join_timeout_s=hub.settings.formation_join_timeout_s,
        scan_source=leader_scans(hub.scans, hub.registry),
        speedup=hub.settings.fleet_speedup,
    )
    await service.close_left_open()
    hub.background.append(service.run)
    hub.scene_layers.append(("formations", formation_scene_layer(service)))
    return service
