"""Health and client configuration."""

from __future__ import annotations

from backend.api.deps import RegistryDep, SettingsDep, SpoolDep, WriterDep
from backend.api.schemas import ClientConfig, Health
from backend.api.security import SecuredRouter, requires
from backend.auth.policy import PUBLIC, Permission
from protocol.messages import PROTOCOL_VERSION

router = SecuredRouter(tags=["system"])


@router.get("/health", response_model=Health, openapi_extra=requires(PUBLIC))
async def health(registry: RegistryDep, writer: WriterDep, spool: SpoolDep) -> Health:
    records = registry.all()
    stats = writer.stats
    return Health(
        status="ok" if stats.database_available else "degraded",
        database_available=stats.database_available,
        vehicles=len(records),
        connected=sum(record.connected for record in records),
        telemetry_backlog=writer.backlog,
        telemetry_written=stats.written,
        write_retries=stats.retries,
        rows_spooled=spool.pending,
        rows_lost=spool.lost,
    )


@router.get("/config", response_model=ClientConfig, openapi_extra=requires(Permission.READ))
async def client_config(settings: SettingsDep) -> ClientConfig:
    """What the dashboard needs to draw itself (base map, protocol version)."""
    return ClientConfig(
        basemap_url=settings.basemap_url,
        basemap_attribution=settings.basemap_attribution,
        basemap_max_zoom=settings.basemap_max_zoom,
        imagery_url=settings.imagery_url,
        imagery_attribution=settings.imagery_attribution,
        imagery_max_zoom=settings.imagery_max_zoom,
        protocol=PROTOCOL_VERSION,
    )
