"""Where the hub finds the dashboard: GCS_FRONTEND_DIR, else the checkout it runs from;
an installed hub (no checkout) is told to set the variable, never sent into site-packages."""

from __future__ import annotations

from pathlib import Path

import httpx

from backend.app import dashboard_dir
from tests.conftest import hub_settings
from tests.support.hub_server import running_hub


def _built(folder: Path) -> Path:
    folder.mkdir(parents=True)
    (folder / "index.html").write_text("<!doctype html><title>dashboard</title>")
    return folder


def test_the_setting_wins(tmp_path: Path) -> None:
    built = _built(tmp_path / "dist")
    assert dashboard_dir(built, tmp_path / "checkout") == (built, "")


def test_a_checkout_serves_its_own_build(tmp_path: Path) -> None:
    (tmp_path / "pyproject.toml").write_text("")
    built = _built(tmp_path / "frontend" / "dist")
    assert dashboard_dir(None, tmp_path) == (built, "")


def test_an_installed_hub_is_told_to_set_the_variable(tmp_path: Path) -> None:
    site_packages = tmp_path / "site-packages"
    _built(site_packages / "frontend" / "dist")  # not a place to look, whatever is there
    found, problem = dashboard_dir(None, site_packages)
    assert found is None
    assert problem == "GCS_FRONTEND_DIR is not set, and this hub does not run from a checkout"


def test_a_wrong_setting_is_named_on_the_page(tmp_path: Path) -> None:
    missing = tmp_path / "nowhere"
    with running_hub(hub_settings(tmp_path, frontend_dir=missing)) as hub:
        page = httpx.get(f"{hub}/")
    assert page.status_code == 503
    assert f"GCS_FRONTEND_DIR={missing} has no index.html." in page.text
    assert "set <code>GCS_FRONTEND_DIR</code>" in page.text
