# The two commands of the README. Both install what they need first.
.PHONY: demo test lint setup setup-dev

VEHICLES ?= 3
# 0.0.0.0 lets a tablet on the field LAN reach the demo (it warns: plain HTTP).
HOST ?= 127.0.0.1
PORT ?= 8000
SPEEDUP ?= 1
# Every feature on show: cameras (gcs demo's default: survey photos and the mosaic) and a
# LIDAR on each drone (scans on the map and in 3D). Four idle drones use about half a core
# with it, a quarter without; DEMO_OPTIONS= leaves it off.
DEMO_OPTIONS ?= --lidar

demo: setup
	.venv/bin/gcs demo --vehicles $(VEHICLES) --host $(HOST) --port $(PORT) --speedup $(SPEEDUP) $(DEMO_OPTIONS)

test: setup-dev
	.venv/bin/python -m pytest

lint: setup-dev
	.venv/bin/ruff check .
	.venv/bin/ruff format --check .
	.venv/bin/mypy
	.venv/bin/lint-imports

setup:
	scripts/setup.sh

setup-dev:
	scripts/setup.sh --dev
