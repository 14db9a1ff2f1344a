"""A meshcat server that listens on one address (default 127.0.0.1), for ``clearance animate --live``.

meshcat's own server (``meshcat.servers.zmqserver``) binds its web server to
every interface while printing ``127.0.0.1``: anyone on the network could watch.
This module runs the same bridge with the web server bound to ``--host`` only,
in a subprocess (like meshcat's), and returns the ZeroMQ URL to connect to.
"""

from __future__ import annotations

import argparse
import atexit
import subprocess
import sys


def start_server(host: str = "127.0.0.1", timeout_lines: int = 50) -> str:
    """Start the server in a subprocess (ended with this process) and return its ``zmq_url``."""
    process = subprocess.Popen(
        [sys.executable, "-u", "-m", "robot.viz.live_server", "--host", host],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    atexit.register(process.terminate)  # the server ends with this process
    for _ in range(timeout_lines):
        line = process.stdout.readline().strip()
        if line.startswith("zmq_url="):
            return line.split("=", 1)[1]
        if process.poll() is not None:
            break
    from robot.errors import RobotError

    raise RobotError(f"the meshcat server did not start on host {host!r}: {process.stderr.read().strip()[-500:]}")


def _serve(host: str) -> None:
    from meshcat.servers import zmqserver

    application_listen = zmqserver.tornado.web.Application.listen

    def listen_on_host(app, port, address="", **kwargs):
        return application_listen(app, port, address=host, **kwargs)

    zmqserver.tornado.web.Application.listen = listen_on_host
    bridge = zmqserver.ZMQWebSocketBridge(host=host)
    print(f"zmq_url={bridge.zmq_url}", flush=True)
    print(f"web_url={bridge.web_url}", flush=True)
    try:
        bridge.run()
    except KeyboardInterrupt:
        pass


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--host", default="127.0.0.1")
    _serve(parser.parse_args().host)
