# One Dockerfile, one image per role, each with only what that role imports:
#   docker build --target hub .        the hub and the built dashboard (fleet-gcs-hub)
#   docker build --target agent .      the vehicle agent, as its wheel (fleet-gcs-agent)
#   docker build --target simulator .  the MAVLink simulator (fleet-gcs-simulator)
# docker-compose.yml builds all three. Every image runs as the unprivileged user gcs
# (uid and gid 10001). tests/packaging/test_image_roles.py reads this file: for each target it
# puts exactly the files the stages copy on a path of their own and checks that the
# role's commands start and every module it ships imports, and that the lock the stage
# installs holds every third-party package they import (no image is built in CI).
# The Python code of the hub and the simulator is their source folders on PYTHONPATH (no
# build step between the copy and what runs); the agent is installed from its wheel, as
# on a drone.

# -- the dashboard: TypeScript to static files ---------------------------------------
FROM node:20-bookworm-slim AS dashboard
WORKDIR /src/frontend
COPY frontend/package.json frontend/package-lock.json ./
COPY frontend/scripts/gen-api/package.json scripts/gen-api/
RUN npm ci --no-audit --no-fund
COPY frontend/ ./
RUN npm run build

# -- what every Python image starts from ---------------------------------------------
FROM python:3.11-slim-bookworm AS python
ENV PYTHONDONTWRITEBYTECODE=1 PYTHONUNBUFFERED=1 \
    PIP_NO_CACHE_DIR=1 PIP_DISABLE_PIP_VERSION_CHECK=1
RUN groupadd --system --gid 10001 gcs \
    && useradd --system --uid 10001 --gid gcs --create-home --home-dir /home/gcs gcs

# -- third-party packages, each role's lock in a virtualenv of its own ---------------
FROM python AS hub-deps
COPY requirements/hub.txt /tmp/
RUN python -m venv /opt/venv \
    && /opt/venv/bin/pip install --require-hashes -r /tmp/hub.txt

FROM python AS simulator-deps
COPY requirements/simulator.txt /tmp/
RUN python -m venv /opt/venv \
    && /opt/venv/bin/pip install --require-hashes -r /tmp/simulator.txt

# The agent's wheel, built as agent/pyproject.toml says (hatchling comes from the index
# here, in the build stage; nothing of it reaches the image), installed as on a drone:
# the lock, the wheel, then pymavlink without the dialects the agent never loads (88 of
# its 92 MB; tests/integration/test_slim_install.py runs the agent on such a pymavlink).
FROM python AS agent-build
WORKDIR /src
COPY agent/ agent/
COPY vehicle_agents/ vehicle_agents/
COPY protocol/ protocol/
COPY common/ common/
COPY requirements/agent.txt /tmp/
RUN pip wheel --no-deps --wheel-dir /dist ./agent \
    && python -m venv /opt/venv \
    && /opt/venv/bin/pip install --require-hashes -r /tmp/agent.txt \
    && /opt/venv/bin/pip install --no-deps /dist/fleet_gcs_agent-*.whl \
    && /opt/venv/bin/python -m vehicle_agents.slim_install

# -- the hub: gcs hub, the API, the dashboard ----------------------------------------
FROM python AS hub
COPY --from=hub-deps /opt/venv /opt/venv
WORKDIR /app
COPY protocol/ protocol/
COPY common/ common/
COPY backend/ backend/
COPY gcs/ gcs/
COPY --from=dashboard /src/frontend/dist /app/frontend/dist
ENV PATH=/opt/venv/bin:$PATH PYTHONPATH=/app \
    GCS_FRONTEND_DIR=/app/frontend/dist GCS_DATA_DIR=/data
# /data: the SQLite database (without DATABASE_URL), uploaded .tlogs, photos, mosaics,
# offline tiles and the spool of audit and command rows kept through a database outage.
# /spool: the spool instead (GCS_SPOOL_DIR=/spool), for hubs that share one /data. A named
# volume mounted on either takes its owner (gcs) from the image's folder.
RUN mkdir -m 700 /data /spool && chown gcs:gcs /data /spool
VOLUME ["/data"]
USER gcs
EXPOSE 8000
HEALTHCHECK --interval=10s --timeout=5s --start-period=60s --retries=3 \
    CMD ["python", "-c", "import urllib.request; urllib.request.urlopen('http://127.0.0.1:8000/api/v1/health', timeout=4)"]
CMD ["python", "-m", "gcs", "hub", "--host", "0.0.0.0", "--port", "8000"]

# -- the vehicle agent: gcs-agent, as installed on a drone ---------------------------
FROM python AS agent
COPY --from=agent-build /opt/venv /opt/venv
ENV PATH=/opt/venv/bin:$PATH \
    GCS_AGENT_OUTBOX_DIR=/var/lib/gcs-agent/outbox \
    GCS_AGENT_TLOG_DIR=/var/lib/gcs-agent/tlogs \
    GCS_AGENT_HEALTH_FILE=/var/lib/gcs-agent/health.json
# The outbox (samples kept while the hub is unreachable), the .tlogs and the photos
# waiting for the hub.
RUN mkdir -p -m 700 /var/lib/gcs-agent && chown gcs:gcs /var/lib/gcs-agent
VOLUME ["/var/lib/gcs-agent"]
USER gcs
# Healthy while the agent hears its flight controller and holds its link to the hub
# (the health file it rewrites every few seconds).
HEALTHCHECK --interval=10s --timeout=5s --start-period=60s --retries=3 \
    CMD ["gcs-agent", "--health"]
ENTRYPOINT ["gcs-agent"]

# -- the simulator: one simulated vehicle per container ------------------------------
FROM python AS simulator
COPY --from=simulator-deps /opt/venv /opt/venv
WORKDIR /app
COPY protocol/ protocol/
COPY common/ common/
COPY simulator/ simulator/
ENV PATH=/opt/venv/bin:$PATH PYTHONPATH=/app
USER gcs
EXPOSE 5760
# Healthy while a MAVLink client connecting to it is sent a HEARTBEAT.
HEALTHCHECK --interval=10s --timeout=5s --start-period=20s --retries=3 \
    CMD ["python", "-m", "simulator.health", "tcp:127.0.0.1:5760"]
ENTRYPOINT ["python", "-m", "simulator"]
