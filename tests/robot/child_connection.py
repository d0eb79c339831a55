"""Run by test_signals.py in a child process: drive a robot until a signal ends it.

    python child_connection.py URL

Prints ``ready`` once the robot is in Safe mode and streaming, then polls and drives until
SIGINT (KeyboardInterrupt) or SIGTERM (Terminated, via sigterm_raises) unwinds the ``with``
block; exits 130 like the CLI does.
"""

from __future__ import annotations

import sys

from roomba_bt.oi import commands as oi
from roomba_bt.oi.encode import Radius
from roomba_bt.robot.connection import Connection
from roomba_bt.robot.safety import sigterm_raises


def main(url: str) -> int:
    try:
        with sigterm_raises(), Connection.open(url, watchdog=0) as connection:
            connection.start("safe", (7, 35))
            print("ready", flush=True)
            while True:
                connection.poll(0.015)
                connection.send(oi.drive(120, Radius.STRAIGHT))
    except KeyboardInterrupt as interrupted:
        print(type(interrupted).__name__, flush=True)
        return 130


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
