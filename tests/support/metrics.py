"""The hub's Prometheus metrics as a test reads them."""

from __future__ import annotations

import re

import httpx


def _value(text: str, series: str) -> float:
    match = re.search(rf"^{re.escape(series)} (\S+)$", text, re.MULTILINE)
    assert match, f"{series} is not in /metrics"
    return float(match.group(1))


def _metrics(hub: str, token: str) -> str:
    response = httpx.get(f"{hub}/metrics", headers={"Authorization": f"Bearer {token}"})
    assert response.status_code == 200, response.text
    assert response.headers["content-type"].startswith("text/plain")
    return response.text
