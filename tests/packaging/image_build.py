"""The Dockerfile's file operations, carried out on a folder instead of an image.

No Docker engine runs where the suite does, so a stage whose COPY lines leave a package
out would go unnoticed until a deployer's container crashed. This reads the Dockerfile
and does, for one target and the stages it copies from, what Docker would do to the
files: the build context as .dockerignore leaves it, FROM (a stage starts as the one it
names), WORKDIR, ENV, COPY (from the context or `--from` another stage), and of RUN the
steps that make or place Python code: `pip wheel` (built here with this environment's
build backend, without the network) and `pip install --no-deps <wheel>` (unpacked into
the venv whose pip it is). `pip install -r <lock>` is recorded in that venv, not run: third-party
packages come from this environment, and the caller checks each one imported is pinned in
that lock. `npm run build` leaves the dashboard's index.html where Vite writes it. Every
other RUN step (users, folders, `npm ci`) touches no Python code and is skipped.
"""

from __future__ import annotations

import glob
import os
import re
import shlex
import shutil
import subprocess
import sys
import zipfile
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath

ROOT = Path(__file__).resolve().parents[2]
SYSTEM = PurePosixPath("/usr/local")
SITE = "site-packages"  # under a venv: where a wheel's packages land, in this model
LOCKS = "installed-locks"  # under a venv: the locks `pip install -r` installed


@dataclass
class Stage:
    name: str
    base: str
    instructions: list[tuple[str, str]] = field(default_factory=list)


@dataclass
class Built:
    """A stage's files (under ``root``, the image's / as a folder) and what it runs."""

    root: Path
    env: dict[str, str] = field(default_factory=dict)
    workdir: PurePosixPath = field(default_factory=lambda: PurePosixPath("/"))
    entrypoint: list[str] = field(default_factory=list)
    cmd: list[str] = field(default_factory=list)
    healthcheck: list[str] = field(default_factory=list)

    def path(self, image_path: PurePosixPath | str) -> Path:
        """Where a path of the image is in this folder."""
        absolute = self.workdir / image_path
        return self.root / str(absolute).lstrip("/")

    def command(self) -> list[str]:
        return [*self.entrypoint, *self.cmd]

    def console_scripts(self, venv: PurePosixPath) -> dict[str, str]:
        """The commands the wheels installed in ``venv`` give: name -> module:func."""
        scripts = {}
        for entry_points in self.path(venv / SITE).glob("*.dist-info/entry_points.txt"):
            section = ""
            for line in entry_points.read_text().splitlines():
                if line.startswith("["):
                    section = line.strip("[]")
                elif section == "console_scripts" and "=" in line:
                    name, _, target = line.partition("=")
                    scripts[name.strip()] = target.strip()
        return scripts


def parse(text: str) -> dict[str, Stage]:
    """The stages of a Dockerfile, each with its instructions (continuations joined)."""
    lines: list[str] = []
    pending = ""
    for raw in text.splitlines():
        if not pending and raw.lstrip().startswith("#"):
            continue
        if raw.rstrip().endswith("\\"):
            pending += raw.rstrip()[:-1] + " "
            continue
        line = (pending + raw).strip()
        pending = ""
        if line and not line.startswith("#"):
            lines.append(line)
    stages: dict[str, Stage] = {}
    current: Stage | None = None
    for line in lines:
        keyword, _, rest = line.partition(" ")
        keyword = keyword.upper()
        if keyword == "FROM":
            words = rest.split()
            name = words[2] if len(words) == 3 and words[1].upper() == "AS" else str(len(stages))
            current = stages[name] = Stage(name, words[0])
        elif current is not None:
            current.instructions.append((keyword, rest.strip()))
    return stages


# -- the build context, as .dockerignore leaves it ------------------------------------


def _pattern(text: str) -> re.Pattern[str]:
    """A .dockerignore pattern (Go's filepath.Match, plus **) as a regular expression."""
    cleaned = os.path.normpath(text.strip().lstrip("/"))
    out = ""
    i = 0
    while i < len(cleaned):
        if cleaned.startswith("**", i):
            out += ".*"
            i += 2
            if cleaned.startswith("/", i):  # **/ also matches no folder at all
                out = out[:-2] + "(?:.*/)?"
                i += 1
        elif cleaned[i] == "*":
            out += "[^/]*"
            i += 1
        elif cleaned[i] == "?":
            out += "[^/]"
            i += 1
        else:
            out += re.escape(cleaned[i])
            i += 1
    return re.compile(out + r"\Z")


def context_files(root: Path = ROOT, dockerignore: str | None = None) -> list[str]:
    """The files Docker would send from ``root``: a path is left out when the last
    .dockerignore pattern that matches it or one of its folders is not a ``!`` one."""
    text = (root / ".dockerignore").read_text() if dockerignore is None else dockerignore
    rules = [
        (line.startswith("!"), _pattern(line.removeprefix("!")))
        for line in (raw.strip() for raw in text.splitlines())
        if line and not line.startswith("#")
    ]
    negations = [pattern for keep, pattern in rules if keep]

    def excluded(relative: str) -> bool:
        parts = relative.split("/")
        verdict = False
        for keep, pattern in rules:
            if any(pattern.match("/".join(parts[:n])) for n in range(1, len(parts) + 1)):
                verdict = not keep
        return verdict

    files = []
    for folder, dirs, names in os.walk(root):
        base = Path(folder).relative_to(root).as_posix()
        prefix = "" if base == "." else base + "/"
        # A left-out folder is not walked unless a ! pattern could let something back in.
        dirs[:] = [
            d
            for d in dirs
            if not excluded(prefix + d)
            or any(p.pattern.startswith(re.escape(prefix + d)) for p in negations)
        ]
        files.extend(prefix + name for name in names if not excluded(prefix + name))
    return sorted(files)


# -- the stages -------------------------------------------------------------------------


class Builder:
    def __init__(self, dockerfile: str, work: Path, context: list[str]) -> None:
        self.stages = parse(dockerfile)
        self.work = work
        self.context = context
        self.built: dict[str, Built] = {}

    def build(self, target: str) -> Built:
        if target in self.built:
            return self.built[target]
        stage = self.stages[target]
        root = self.work / target
        if stage.base in self.stages:
            parent = self.build(stage.base)
            shutil.copytree(parent.root, root, symlinks=True)
            built = Built(
                root,
                dict(parent.env),
                parent.workdir,
                list(parent.entrypoint),
                list(parent.cmd),
                list(parent.healthcheck),
            )
        else:
            root.mkdir(parents=True)
            built = Built(root)
        for keyword, rest in stage.instructions:
            if keyword == "WORKDIR":
                built.workdir = built.workdir / rest
                built.path(".").mkdir(parents=True, exist_ok=True)
            elif keyword == "ENV":
                built.env.update(env_values(rest, built.env))
            elif keyword == "COPY":
                self._copy(built, rest)
            elif keyword == "RUN":
                for step in re.split(r"\s*&&\s*", rest):
                    self._run(built, shlex.split(step))
            elif keyword in ("CMD", "ENTRYPOINT"):
                words = _exec_form(rest)
                if keyword == "ENTRYPOINT":
                    built.entrypoint, built.cmd = words, []
                else:
                    built.cmd = words
            elif keyword == "HEALTHCHECK":
                built.healthcheck = _exec_form(rest[rest.index("CMD") + 3 :])
        self.built[target] = built
        return built

    def _copy(self, built: Built, rest: str) -> None:
        words = shlex.split(rest)
        source_stage = None
        while words[0].startswith("--"):
            flag = words.pop(0)
            if flag.startswith("--from="):
                source_stage = self.build(flag.removeprefix("--from="))
        *sources, destination = words
        for source in sources:
            if source_stage is None:
                matched = [name for name in self.context if _under(name, source.rstrip("/"))]
                if not matched:
                    raise FileNotFoundError(f"COPY {source}: not in the build context")
                source_root = PurePosixPath(source.rstrip("/"))
                pairs = [(ROOT / name, PurePosixPath(name)) for name in matched]
                is_folder = any(name != str(source_root) for name in matched)
            else:
                pattern = str(source_stage.root) + "/" + source.lstrip("/")
                found = [Path(p) for p in glob.glob(pattern)]
                if not found:
                    raise FileNotFoundError(f"COPY --from: {source} does not exist")
                pairs = []
                for path in found:
                    if path.is_dir():
                        pairs += [
                            (f, PurePosixPath(f.relative_to(source_stage.root).as_posix()))
                            for f in path.rglob("*")
                            if f.is_file()
                        ]
                    else:
                        pairs.append((path, PurePosixPath(path.relative_to(source_stage.root))))
                source_root = PurePosixPath(found[0].relative_to(source_stage.root).as_posix())
                is_folder = found[0].is_dir()
            for file, relative in pairs:
                if is_folder:  # a folder's contents go into the destination
                    target = built.path(destination) / relative.relative_to(source_root)
                elif destination.endswith("/"):
                    target = built.path(destination) / relative.name
                else:
                    target = built.path(destination)
                target.parent.mkdir(parents=True, exist_ok=True)
                shutil.copy2(file, target)

    def _run(self, built: Built, words: list[str]) -> None:
        if not words:
            return
        pip = words[0] == "pip" or words[0].endswith("/bin/pip")
        # A venv's own pip installs into that venv; the system's into the system's Python.
        venv = PurePosixPath(words[0]).parent.parent if "/" in words[0] else SYSTEM
        if pip and "wheel" in words:
            source = words[-1]
            out = words[words.index("--wheel-dir") + 1]
            built.path(out).mkdir(parents=True, exist_ok=True)
            subprocess.run(
                [
                    *(sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation"),
                    *("-q", "--wheel-dir", str(built.path(out)), str(built.path(source))),
                ],
                check=True,
                timeout=120,
                cwd=built.path("."),
            )
        elif pip and "install" in words and "-r" in words:
            # Recorded in the venv itself, so a COPY --from of the venv carries it.
            lock = built.path(words[words.index("-r") + 1])
            locks = built.path(venv / LOCKS)
            locks.mkdir(parents=True, exist_ok=True)
            shutil.copy2(lock, locks / lock.name)
        elif pip and "install" in words:
            for pattern in (w for w in words[words.index("install") + 1 :] if w[0] != "-"):
                wheels = glob.glob(str(built.path(pattern)))
                if len(wheels) != 1 or not wheels[0].endswith(".whl"):
                    raise AssertionError(f"RUN pip install {pattern}: expected one wheel")
                with zipfile.ZipFile(wheels[0]) as archive:
                    archive.extractall(built.path(venv / SITE))
        elif words[:3] == ["python", "-m", "venv"]:
            built.path(words[3]).mkdir(parents=True, exist_ok=True)
        elif words[:3] == ["npm", "run", "build"]:
            # Vite writes the dashboard to dist/ (frontend/vite.config.ts's outDir).
            vite = (ROOT / "frontend" / "vite.config.ts").read_text()
            assert 'outDir: "dist"' in vite, "the dashboard's build output moved"
            (built.path("dist")).mkdir(parents=True, exist_ok=True)
            (built.path("dist") / "index.html").write_text("<!-- npm run build -->")


def _under(name: str, source: str) -> bool:
    return source in (".", name) or name.startswith(source + "/")


def env_values(text: str, env: dict[str, str]) -> dict[str, str]:
    values = {}
    for word in shlex.split(text):
        name, _, value = word.partition("=")
        values[name] = re.sub(r"\$(\w+)", lambda m: env.get(m.group(1), ""), value)
    return values


def _exec_form(text: str) -> list[str]:
    import json

    words = json.loads(text.strip())
    assert isinstance(words, list), f"not an exec form: {text}"
    return [str(word) for word in words]
