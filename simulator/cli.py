"""``python -m simulator`` / ``gcs sim``: run one simulated vehicle."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import signal

from simulator.config import SimulatorConfig, parse_args
from simulator.server import SimulatorServer
from simulator.vehicles import build_vehicle

log = logging.getLogger("simulator")

LOG_FORMAT = "%(asctime)s %(levelname)-7s %(name)s: %(message)s"


def main(argv: list[str] | None = None) -> int:
    """Run until SIGINT/SIGTERM; 0 on a clean stop, 1 if it cannot listen, 2 on bad usage."""
    try:
        config = parse_args(argv)
    except SystemExit as exit_request:  # argparse: --help, or a bad argument
        code = exit_request.code
        return code if isinstance(code, int) else (0 if code is None else 2)
    logging.basicConfig(level=config.log_level, format=LOG_FORMAT)
    log.setLevel(config.log_level)
    try:
        build_vehicle(config)  # a bad --param is said now, not after the server starts
    except ValueError as error:
        log.error("%s", error)
        return 2
    try:
        asyncio.run(run(config))
    except OSError as error:
        log.error("cannot listen on %s: %s", config.listen, error)
        return 1
    except KeyboardInterrupt:  # only where signal handlers could not be installed
        pass
    return 0


async def run(config: SimulatorConfig) -> None:
    """Serve ``config`` until the process is asked to stop."""
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    for signum in (signal.SIGINT, signal.SIGTERM):
        # not possible off the main thread or on Windows: then Ctrl-C raises instead
        with contextlib.suppress(NotImplementedError, RuntimeError, ValueError):
            loop.add_signal_handler(signum, stop.set)
    await SimulatorServer(config).serve(stop)
