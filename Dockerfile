# One image for the hub, the agent and the simulator.
FROM node:20-bookworm-slim AS dashboard
WORKDIR /src/frontend
COPY frontend/package.json frontend/package-lock.json ./
COPY frontend/scripts/gen-api/package.json scripts/gen-api/
RUN npm ci --no-audit --no-fund
COPY frontend/ ./
RUN npm run build

FROM python:3.11-slim-bookworm
WORKDIR /app
COPY requirements/hub.txt requirements/
RUN pip install --no-cache-dir --require-hashes -r requirements/hub.txt
COPY pyproject.toml README.md ./
COPY gcs/ gcs/
COPY backend/ backend/
COPY vehicle_agents/ vehicle_agents/
RUN pip install --no-cache-dir --no-deps .
COPY --from=dashboard /src/frontend/dist /app/frontend/dist
ENV GCS_FRONTEND_DIR=/app/frontend/dist GCS_DATA_DIR=/data
RUN useradd --system --create-home gcs && mkdir /data && chown gcs /data
USER gcs
EXPOSE 8000
CMD ["gcs", "hub", "--host", "0.0.0.0", "--port", "8000"]
