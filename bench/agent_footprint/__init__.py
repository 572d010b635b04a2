"""The parts of bench/bench_agent.py: the MAVLink source it feeds the agent from, and the
processes it starts and measures through /proc."""
