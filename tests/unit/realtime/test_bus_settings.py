"""The hubs' NATS credentials (docs/deployer.md, "Several hubs"): a hub outside development refuses
a bus it would join without a login, and the URL's secret never reaches a log."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from pydantic import ValidationError

from backend.realtime.fleet_link import bus_credentials
from backend.settings import HubSettings, redacted_url

PASSWORD = "a-bus-password-nobody-guesses"


@pytest.fixture(autouse=True)
def _no_bus_settings_from_the_machine(monkeypatch: pytest.MonkeyPatch) -> None:
    for name in ("GCS_BUS_URL", "GCS_BUS_USER", "GCS_BUS_PASSWORD", "GCS_BUS_PASSWORD_FILE"):
        monkeypatch.delenv(name, raising=False)


def test_outside_development_a_bus_without_credentials_is_refused(tmp_path: Path) -> None:
    with pytest.raises(ValidationError, match="GCS_BUS_URL nats://nats:4222 carries no cred"):
        HubSettings(data_dir=tmp_path, bus_url="nats://nats:4222")
    # The development exception: a trial on one machine joins the machine's open NATS.
    HubSettings(data_dir=tmp_path, environment="development", bus_url="nats://nats:4222")


@pytest.mark.parametrize(
    "credentials",
    [
        {"bus_user": "gcs-hub", "bus_password": PASSWORD},
        {"bus_url": f"nats://gcs-hub:{PASSWORD}@nats:4222"},
        {"bus_url": f"nats://{PASSWORD}@nats:4222"},  # a token
        {"bus_creds_file": Path("/run/secrets/hub.creds")},
    ],
    ids=["user-password", "url-user-password", "url-token", "creds-file"],
)
def test_a_bus_with_credentials_is_accepted(tmp_path: Path, credentials: dict[str, Any]) -> None:
    settings = HubSettings(data_dir=tmp_path, **{"bus_url": "nats://nats:4222", **credentials})
    assert settings.bus_has_credentials


def test_a_default_bus_password_is_refused_and_a_user_needs_a_password(tmp_path: Path) -> None:
    with pytest.raises(ValidationError, match="GCS_BUS_PASSWORD is a default"):
        HubSettings(
            data_dir=tmp_path, bus_url="nats://nats:4222", bus_user="gcs", bus_password="secret"
        )
    with pytest.raises(ValidationError, match="GCS_BUS_USER and GCS_BUS_PASSWORD go together"):
        HubSettings(data_dir=tmp_path, environment="development", bus_user="gcs-hub")


def test_the_bus_password_can_come_from_a_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    secret = tmp_path / "bus_password"
    secret.write_text(PASSWORD + "\n")
    monkeypatch.setenv("GCS_BUS_PASSWORD_FILE", str(secret))
    settings = HubSettings(data_dir=tmp_path, bus_url="nats://nats:4222", bus_user="gcs-hub")
    assert bus_credentials(settings) == {"user": "gcs-hub", "password": PASSWORD}
    assert PASSWORD not in repr(settings)


def test_a_refusal_and_the_log_show_the_url_without_its_secret(tmp_path: Path) -> None:
    url = f"nats://gcs-hub:{PASSWORD}@nats:4222"
    assert redacted_url(url) == "nats://gcs-hub:***@nats:4222"
    assert redacted_url(f"tls://{PASSWORD}@nats") == "tls://***@nats"
    assert redacted_url("nats://nats:4222") == "nats://nats:4222"
    with pytest.raises(ValidationError) as refused:
        HubSettings(data_dir=tmp_path, bus_url="nats://gcs-hub:admin@nats:4222", admin_password="x")
    assert "admin@nats" not in str(refused.value)
