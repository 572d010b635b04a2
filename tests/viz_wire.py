"""viser's wire format, read the way its browser client reads it, for the 3D view's tests."""

from __future__ import annotations

from typing import Any

import msgspec
import viser
import zstandard
from websockets.sync.client import ClientConnection, connect
from websockets.typing import Subprotocol

from backend.viz3d.server import VizServer

SUBPROTOCOL = f"viser-v{viser.__version__}"


def scene_socket(viz: VizServer, headers: dict[str, str] | None = None) -> ClientConnection:
    """A socket to viser's own port, as the hub's relay opens it: with this start's key
    unless ``headers`` says otherwise."""
    return connect(
        viz.ws_url,
        subprotocols=[Subprotocol(SUBPROTOCOL)],
        additional_headers=viz.relay_headers if headers is None else headers,
    )


def scene_messages(frame: bytes) -> list[dict[str, Any]]:
    """The messages of one frame: 8 bytes of plain size, 8 of compressed size, then the
    zstd-compressed msgpack (binary arrays follow it, and are not decoded here)."""
    plain = int.from_bytes(frame[0:8], "little")
    packed = int.from_bytes(frame[8:16], "little")
    inner = zstandard.ZstdDecompressor().decompress(frame[16 : 16 + packed], plain)
    messages: list[dict[str, Any]] = msgspec.msgpack.decode(inner)["messages"]
    return messages


def viewer_camera() -> bytes:
    """What a browser sends first: its camera. viser counts a viewer as connected (and
    calls ``on_client_connect``) only once this has arrived."""
    from viser import _messages as viser_messages

    camera = viser_messages.ViewerCameraMessage(
        wxyz=(1.0, 0.0, 0.0, 0.0),
        position=(0.0, -50.0, 30.0),
        fov=1.0,
        near=0.01,
        far=1000.0,
        image_height=480,
        image_width=640,
        look_at=(0.0, 0.0, 0.0),
        up_direction=(0.0, 0.0, 1.0),
    )
    # The client sends plain msgpack (the server reads it with Message.deserialize).
    return msgspec.msgpack.encode(camera.as_serializable_dict())
