"""Each image of the Dockerfile holds what its role runs, and nothing of the other roles.

No Docker engine runs here, so each target is built as a folder (tests/packaging/
image_build.py: the context as .dockerignore leaves it, the COPY lines, the agent's wheel
built and installed as its stage does). Then, with a Python that sees only that folder's
code (its PYTHONPATH and its venv's wheels) and this environment's third-party packages:
every module the image ships imports, with only the third-party packages pinned in the
lock the image installed, and the role's command answers --help. An image that
left a package out fails here as it would have crashed in a container.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
import sysconfig
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from importlib.metadata import packages_distributions
from pathlib import Path, PurePosixPath

import pytest
from packaging.utils import canonicalize_name

from tests.packaging.image_build import LOCKS, ROOT, SITE, Builder, Built, context_files

pytestmark = pytest.mark.slow

DOCKERFILE = (ROOT / "Dockerfile").read_text()
THIRD_PARTY = Path(sysconfig.get_paths()["purelib"])
VENV = PurePosixPath("/opt/venv")
PIN = re.compile(r"^([A-Za-z0-9][A-Za-z0-9._-]*)==", re.MULTILINE)


@dataclass(frozen=True)
class Role:
    packages: frozenset[str]  # exactly the project's packages the image must hold
    answers: str  # a word the command's --help prints
    # Third-party packages of an optional extra the image leaves out: the modules that
    # need them (and only those) may not import.
    optional: dict[str, frozenset[str]] = field(default_factory=dict)


ROLES = {
    "hub": Role(frozenset({"gcs", "backend", "protocol", "common"}), "--data-dir"),
    # A USB or CSI camera needs OpenCV (the agent's `camera` extra), which would make
    # the image some 60 MB larger for a drone that has none: as the agent's wheel.
    "agent": Role(
        frozenset({"vehicle_agents", "protocol", "common"}),
        "--fcu",
        {"camera": frozenset({"cv2", "numpy"})},
    ),
    "simulator": Role(frozenset({"simulator", "protocol", "common"}), "--listen"),
}
OURS = set().union(*(role.packages for role in ROLES.values()))
# The modules of each extra's: what may be skipped, and nothing else.
SKIPPED = {"agent": {"common.opencv"}}


def _code_paths(image: Built) -> list[Path]:
    """Where the image's Python finds our code: PYTHONPATH and its venv's packages."""
    paths = [image.path(p) for p in image.env.get("PYTHONPATH", "").split(":") if p]
    return [*paths, image.path(VENV / SITE)]


def _python(image: Built, code: str, *, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    """``code`` in a Python that sees what the image's would: the image's code, and of
    this environment's third-party packages only those its locks pin (the others are made
    unimportable). -I: not this process's PYTHONPATH, nor the current folder; -S: no site,
    so the editable install's .pth (the checkout) is not read."""
    paths = [str(p) for p in _code_paths(image)] + [str(THIRD_PARTY)]
    preamble = (
        "import sys\n"
        f"sys.path[:0] = {paths!r}\n"
        f"for name in {sorted(_unpinned(image))!r}: sys.modules[name] = None\n"
    )
    return subprocess.run(
        [sys.executable, "-I", "-S", "-c", preamble + code],
        capture_output=True,
        text=True,
        timeout=timeout,
        cwd=image.path(VENV),
        check=False,
    )


def _unpinned(image: Built) -> set[str]:
    """The top-level modules of this environment that no lock of the image pins."""
    pinned = {
        canonicalize_name(name)
        for lock in image.path(VENV / LOCKS).glob("*.txt")
        for name in PIN.findall(lock.read_text())
    }
    assert pinned, f"the image installs no lock into {VENV}"
    return {
        module
        for module, dists in packages_distributions().items()
        if module not in OURS and not {canonicalize_name(d) for d in dists} & pinned
    }


IMPORT_ALL = """
import importlib, json, pkgutil
skipped = []

def load(name):
    try:
        return importlib.import_module(name)
    except ModuleNotFoundError as error:
        if (error.name or "").partition(".")[0] not in {optional!r}:
            raise
        skipped.append(name)

def reraise(name):
    raise  # walk_packages calls this while handling the package's ImportError

for package in {packages!r}:
    root = load(package)
    for info in pkgutil.walk_packages(root.__path__, package + ".", onerror=reraise):
        if not info.name.endswith(".__main__"):  # that one runs the program
            load(info.name)
modules = {{name: getattr(m, "__file__", None) for name, m in sys.modules.items()}}
print(json.dumps({{"modules": modules, "skipped": skipped}}))
"""


def _shipped(image: Built) -> set[str]:
    """The top-level packages of our project the image holds."""
    return {
        entry.name
        for folder in _code_paths(image)
        if folder.is_dir()
        for entry in folder.iterdir()
        if entry.name in OURS and (entry / "__init__.py").exists()
    }


def _help(image: Built, command: list[str]) -> subprocess.CompletedProcess[str]:
    """The image's command with --help after its subcommands (its options dropped)."""
    words = [*command]
    if words[:2] == ["python", "-m"]:
        module, rest = words[2], words[3:]
        start = f"import runpy\nrunpy.run_module({module!r}, run_name='__main__', alter_sys=True)"
    else:
        scripts = image.console_scripts(VENV)
        assert words[0] in scripts, f"{words[0]} is not a command of the image: {scripts}"
        module, _, function = scripts[words[0]].partition(":")
        rest = words[1:]
        start = f"from {module} import {function}\nsys.exit({function}())"
    subcommands = []
    for word in rest:
        if word.startswith("-"):
            break
        subcommands.append(word)
    argv = [words[0], *subcommands, "--help"]
    return _python(image, f"sys.argv = {argv!r}\n{start}\n")


def check_contents(target: str, image: Built) -> None:
    """The image holds exactly the packages of our project its role needs."""
    role = ROLES[target]
    shipped = _shipped(image)
    assert shipped == role.packages, (
        f"the {target} image holds {sorted(shipped)}, its role needs {sorted(role.packages)}"
    )


def check_runs(target: str, image: Built) -> None:
    """Fails with the reason when the image cannot run its role."""
    role = ROLES[target]
    assert image.env["PATH"].startswith(f"{VENV}/bin:"), "the image's python is not its venv's"
    shipped = _shipped(image)
    optional = sorted(set().union(*role.optional.values()))
    imported = _python(image, IMPORT_ALL.format(packages=sorted(shipped), optional=optional))
    assert imported.returncode == 0, (
        f"the {target} image's modules do not import:\n{imported.stderr.strip()}"
    )
    result = json.loads(imported.stdout)
    files: dict[str, str | None] = result["modules"]
    assert set(result["skipped"]) == SKIPPED.get(target, set()), result["skipped"]
    # Our code came from the image's folder, never from the checkout.
    for name, file in files.items():
        if name.partition(".")[0] in role.packages:
            assert file is None or file.startswith(str(image.root)), (name, file)
    answered = _help(image, image.command())
    assert answered.returncode == 0, (
        f"`{' '.join(image.command())} --help` fails in the {target} image:\n{answered.stderr}"
    )
    assert role.answers in answered.stdout
    # The health check runs something the image has.
    probe = image.healthcheck
    assert probe, f"the {target} image has no HEALTHCHECK"
    if probe[:2] == ["python", "-m"]:
        assert probe[2] in files, f"HEALTHCHECK runs {probe[2]}, which the image lacks"
    elif probe[0] != "python":
        assert probe[0] in image.console_scripts(VENV), f"HEALTHCHECK runs {probe[0]}"


@pytest.fixture(scope="module")
def context() -> list[str]:
    return context_files()


@pytest.fixture(scope="module")
def builder(tmp_path_factory: pytest.TempPathFactory, context: list[str]) -> Builder:
    return Builder(DOCKERFILE, tmp_path_factory.mktemp("images"), context)


# The Dockerfile with `common/` left out of the hub's stage (as `protocol/` and `common/`
# were once left out of the one image, which then crashed at its first import).
WITHOUT_COMMON = DOCKERFILE.replace("COPY common/ common/\nCOPY backend/", "COPY backend/")


@pytest.fixture(scope="module")
def runs(
    builder: Builder, tmp_path_factory: pytest.TempPathFactory, context: list[str]
) -> dict[str, Exception | None]:
    """check_runs of each role, and of the hub without common/, side by side: each waits
    mostly on its imports' disk reads, so together they take the time of the slowest."""
    images = {target: builder.build(target) for target in ROLES}
    broken = Builder(WITHOUT_COMMON, tmp_path_factory.mktemp("broken"), context).build("hub")

    def outcome(target: str, image: Built) -> Exception | None:
        try:
            check_runs(target, image)
        except Exception as error:
            return error
        return None

    with ThreadPoolExecutor(len(images) + 1) as pool:
        futures = {name: pool.submit(outcome, name, image) for name, image in images.items()}
        futures["hub without common"] = pool.submit(outcome, "hub", broken)
        return {name: future.result() for name, future in futures.items()}


@pytest.mark.parametrize("target", sorted(ROLES))
def test_each_image_runs_its_role(
    builder: Builder, runs: dict[str, Exception | None], target: str
) -> None:
    check_contents(target, builder.build(target))
    if runs[target] is not None:
        raise runs[target]


def test_the_hub_image_serves_the_built_dashboard(builder: Builder) -> None:
    hub = builder.build("hub")
    assert (hub.path(hub.env["GCS_FRONTEND_DIR"]) / "index.html").is_file()
    assert hub.env["GCS_DATA_DIR"] == "/data"


def test_every_image_runs_as_an_unprivileged_user() -> None:
    stages = Builder(DOCKERFILE, Path("/nonexistent"), []).stages
    for target in ROLES:
        users = [rest for keyword, rest in stages[target].instructions if keyword == "USER"]
        assert users == ["gcs"], target


def test_the_build_context_leaves_out_the_checkout_s_bulk(context: list[str]) -> None:
    size = sum((ROOT / name).stat().st_size for name in context)
    assert size < 20 * 2**20, f"the build context is {size / 2**20:.1f} MiB"
    for left_out in (".git/", ".venv/", "frontend/node_modules/", "test-output/", "data/"):
        assert not any(name.startswith(left_out) for name in context), left_out
    assert not any("__pycache__" in name for name in context)
    assert "frontend/package-lock.json" in context
    assert "requirements/hub.txt" in context


def test_an_image_that_leaves_a_package_out_fails(
    tmp_path: Path, context: list[str], runs: dict[str, Exception | None]
) -> None:
    """Both checks fail on the hub's stage without `COPY common/`."""
    assert WITHOUT_COMMON.count("COPY common/") == DOCKERFILE.count("COPY common/") - 1
    image = Builder(WITHOUT_COMMON, tmp_path, context).build("hub")
    with pytest.raises(AssertionError, match=r"holds \['backend', 'gcs', 'protocol'\]"):
        check_contents("hub", image)
    failure = runs["hub without common"]
    assert isinstance(failure, AssertionError)
    assert "No module named 'common'" in str(failure)
