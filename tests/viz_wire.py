"""viser's wire format, read the way its browser client reads it, for the 3D view's tests."""

from __future__ import annotations

from typing import Any

import msgspec
import viser
import zstandard

SUBPROTOCOL = f"viser-v{viser.__version__}"


def scene_messages(frame: bytes) -> list[dict[str, Any]]:
    """The messages of one frame: 8 bytes of plain size, 8 of compressed size, then the
    zstd-compressed msgpack (binary arrays follow it, and are not decoded here)."""
    plain = int.from_bytes(frame[0:8], "little")
    packed = int.from_bytes(frame[8:16], "little")
    inner = zstandard.ZstdDecompressor().decompress(frame[16 : 16 + packed], plain)
    messages: list[dict[str, Any]] = msgspec.msgpack.decode(inner)["messages"]
    return messages
