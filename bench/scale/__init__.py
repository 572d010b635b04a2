"""The parts of bench/bench_scale.py: agents, dashboards, the hub process, the figures."""
