"""The two WebSocket endpoints: agents, and clients (dashboards, integrations)."""

from __future__ import annotations

from fastapi import APIRouter, WebSocket

from backend.api.deps import FeedServicesDep, GatewayServicesDep
from backend.realtime.agent_gateway.session import AgentSession
from backend.realtime.client_feed import ClientFeed
from protocol.messages import AGENT_WS_PATH, CLIENT_WS_PATH

router = APIRouter()


@router.websocket(AGENT_WS_PATH)
async def agent_socket(websocket: WebSocket, services: GatewayServicesDep) -> None:
    await AgentSession(websocket, services).serve()


@router.websocket(CLIENT_WS_PATH)
async def client_socket(websocket: WebSocket, services: FeedServicesDep) -> None:
    await ClientFeed(websocket, services).serve()
