"""`gcs hub --ssl-certfile/--ssl-keyfile` serves HTTPS directly (no reverse proxy)."""

from __future__ import annotations

import os
import shutil
import ssl
import subprocess
import sys
from pathlib import Path

import httpx
import pytest

from gcs.launcher import free_port

pytestmark = pytest.mark.integration


def test_hub_serves_https_with_uvicorn_flags(tmp_path: Path) -> None:
    openssl = shutil.which("openssl")
    assert openssl, "openssl is part of every Debian install"
    cert, key = tmp_path / "cert.pem", tmp_path / "key.pem"
    subprocess.run(
        [
            openssl,
            "req",
            "-x509",
            "-newkey",
            "rsa:2048",
            "-nodes",
            "-days",
            "1",
            "-subj",
            "/CN=127.0.0.1",
            "-addext",
            "subjectAltName=IP:127.0.0.1",
            "-keyout",
            str(key),
            "-out",
            str(cert),
        ],
        check=True,
        capture_output=True,
        timeout=60,
    )
    port = free_port()
    env = {**os.environ, "GCS_ENVIRONMENT": "development", "GCS_ADMIN_PASSWORD": "tls-test-pw"}
    with subprocess.Popen(
        [
            sys.executable,
            "-m",
            "gcs",
            "hub",
            "--port",
            str(port),
            "--data-dir",
            str(tmp_path),
            "--ssl-certfile",
            str(cert),
            "--ssl-keyfile",
            str(key),
        ],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    ) as hub:
        try:
            assert hub.stdout is not None
            for line in hub.stdout:  # uvicorn announces the scheme it serves
                if "Uvicorn running on" in line:
                    assert "https://" in line
                    break
            health = httpx.get(
                f"https://127.0.0.1:{port}/api/v1/health",
                verify=ssl.create_default_context(cafile=str(cert)),
            )
            assert health.status_code == 200
        finally:
            hub.terminate()
            hub.wait(10)
