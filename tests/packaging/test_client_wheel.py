"""The client's wheel (client/pyproject.toml) holds gcs_client alone and runs without the
rest of this repository: what an integrator installs."""

from __future__ import annotations

import re
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path, PurePosixPath

import pytest

ROOT = Path(__file__).resolve().parents[2]
PIP_WHEEL = [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q"]
# None of our other packages, nor what only the hub, the agent or the protocol need.
NOT_IN_THE_CLIENT = [
    "protocol",
    "common",
    "vehicle_agents",
    "simulator",
    "backend",
    "gcs",
    "fastapi",
    "starlette",
    "uvicorn",
    "sqlalchemy",
    "pymavlink",
]


@pytest.fixture(scope="module")
def client_wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("wheel")
    subprocess.run(
        [*PIP_WHEEL, "--wheel-dir", str(out), str(ROOT / "client")], check=True, timeout=120
    )
    (wheel,) = out.glob("fleet_gcs_client-*.whl")
    return wheel


def test_the_client_wheel_holds_gcs_client_only(client_wheel: Path) -> None:
    with zipfile.ZipFile(client_wheel) as wheel:
        names = [PurePosixPath(name) for name in wheel.namelist()]
    packages = {name.parts[0] for name in names if not name.parts[0].endswith(".dist-info")}
    assert packages == {"gcs_client"}
    shipped = {name.name for name in names if name.parts[0] == "gcs_client"}
    assert {"__init__.py", "hub.py", "sync.py", "feed.py", "errors.py", "models.py"} <= shipped
    assert {name.suffix for name in names if name.parts[0] == "gcs_client"} == {".py"}


def test_the_client_asks_for_what_the_project_pins() -> None:
    """Its dependencies' lower bounds are the main project's (which the locks satisfy)."""
    client = tomllib.loads((ROOT / "client" / "pyproject.toml").read_text())["project"]
    full = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    everything = set(full["dependencies"]) | set(full["optional-dependencies"]["hub"])
    stripped = {re.sub(r"\s*#.*", "", spec) for spec in everything}
    assert set(client["dependencies"]) <= stripped
    assert client["version"] == full["version"]


def test_the_client_runs_from_its_wheel_alone(client_wheel: Path, tmp_path: Path) -> None:
    with zipfile.ZipFile(client_wheel) as wheel:
        wheel.extractall(tmp_path)
    script = (
        "import sys\n"
        f"sys.path.insert(0, {str(tmp_path)!r})\n"
        f"for name in {NOT_IN_THE_CLIENT!r}: sys.modules[name] = None\n"
        "import gcs_client, gcs_client.models\n"
        f"assert gcs_client.__file__.startswith({str(tmp_path)!r}), gcs_client.__file__\n"
        "try:\n"
        "    gcs_client.Hub('http://127.0.0.1:1')\n"
        "except gcs_client.MissingCredentials as error:\n"
        "    print(error)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=60, cwd=tmp_path
    )
    assert done.returncode == 0, done.stderr
    assert "a username and password" in done.stdout
