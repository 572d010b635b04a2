"""Several hubs on one database and a NATS bus (GCS_BUS_URL): this hub's services joined to
the others' through the fleet link, once they are built and before they load."""

from __future__ import annotations

from sqlalchemy import Engine

from backend.auth.policy import Principal
from backend.fleet.collaborators import CommandServices
from backend.fleet.command_service import carry_out_routed
from backend.hub.collaborators import RoutedSenders
from backend.manual_control.claims import LeaseClaims
from backend.manual_control.service import ManualControl
from backend.realtime.fleet_link import FleetLink
from backend.storage.claims import LeaseClaimStore
from backend.survey.ownership import SurveyOwnership
from backend.survey.service import SurveyService
from protocol.messages import CommandOutcome
from protocol.routing import RoutedCommand


def link_hubs(
    fleet_link: FleetLink,
    engine: Engine,
    commands: CommandServices,
    senders: RoutedSenders,
    manual_control: ManualControl,
    surveys: SurveyService,
) -> None:
    """Leases and surveys claimed in the shared database, so one hub holds each at a time;
    browser control ended on another hub ends here; commands other hubs route to the
    agents this hub holds are checked (their sender) and carried out."""
    claims = LeaseClaims(LeaseClaimStore(engine), fleet_link.hub_id, fleet_link.lease_ttl_s)
    manual_control.leases.claims = claims
    surveys.ownership = SurveyOwnership(LeaseClaimStore(engine), fleet_link.hub_id)
    fleet_link.on_manual_ended = manual_control.end_on_vehicle

    async def carry_out(
        principal: Principal, vehicle_id: str, routed: RoutedCommand
    ) -> CommandOutcome:
        return await carry_out_routed(commands, principal, vehicle_id, routed)

    fleet_link.routes.check_sender = senders
    fleet_link.routes.carry_out = carry_out
