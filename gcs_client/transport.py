"""What every request of the client shares: the bearer header, query parameters without
their unset ones, and the error for a hub that does not answer."""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

import httpx

from gcs_client.errors import HubUnreachable


def bearer(token: str) -> dict[str, str]:
    return {"Authorization": f"Bearer {token}"}


def without_none(params: Mapping[str, Any]) -> dict[str, Any]:
    return {key: value for key, value in params.items() if value is not None}


def unreachable(url: str, error: httpx.TransportError) -> HubUnreachable:
    """No answer from the hub, with the operating system's reason where there is one
    (httpx's async transport says only "All connection attempts failed")."""
    cause: BaseException | None = error
    while cause is not None and not (isinstance(cause, OSError) and cause.errno):
        cause = cause.__cause__ or cause.__context__
    reason = os.strerror(cause.errno) if isinstance(cause, OSError) and cause.errno else str(error)
    return HubUnreachable(f"cannot reach the hub at {url}: {reason or type(error).__name__}")
