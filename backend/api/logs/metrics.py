"""The storage path's health."""

from __future__ import annotations

from pydantic import BaseModel

from backend.api.deps import RegistryDep, WriterDep
from backend.api.security import SecuredRouter, requires
from backend.auth.policy import Permission

router = SecuredRouter(tags=["flight log"])


class Metrics(BaseModel):
    telemetry_written: int
    events_written: int
    batches: int
    write_retries: int
    database_available: bool
    writer_backlog: int
    writer_capacity: int
    last_batch_s: float
    connected_agents: int


@router.get("/metrics", response_model=Metrics, openapi_extra=requires(Permission.READ))
async def metrics(registry: RegistryDep, writer: WriterDep) -> Metrics:
    """The storage path's health: backlog against capacity shows backpressure building."""
    stats = writer.stats
    return Metrics(
        telemetry_written=stats.written,
        events_written=stats.events_written,
        batches=stats.batches,
        write_retries=stats.retries,
        database_available=stats.database_available,
        writer_backlog=writer.backlog,
        writer_capacity=writer.capacity,
        last_batch_s=stats.last_batch_s,
        connected_agents=sum(record.connected for record in registry.all()),
    )
