"""The live monitor: a page in the browser that shows a running (or recorded) mission's tree,
robot, path, blackboard and events, and lets an operator pause, resume, step, stop, set
breakpoints and force conditions.

Layers: the monitor sits beside ``cli`` (it reads the runtime and, for the simulator's truth,
the simulator). Its pieces, each usable without the others:

* :mod:`~roomba_bt.monitor.feed`: the bounded per-tick history the tick thread appends to
  (never blocks, never waits for a page);
* :mod:`~roomba_bt.monitor.session`: the runtime's tick gate: operator requests (pause,
  resume, step, stop, force, breakpoints, reload) applied between ticks, each checked first
  (:mod:`~roomba_bt.monitor.controls`: what may be asked, and when it is refused);
* :mod:`~roomba_bt.monitor.server`: the web server (aiohttp, an optional extra) in a thread of
  its own, serving :mod:`~roomba_bt.monitor.routes` (what each URL answers, and who may ask:
  the page in ``static/``, its API) and, on each page's socket, the updates'
  :mod:`~roomba_bt.monitor.pump`;
* :mod:`~roomba_bt.monitor.recorded`: a ``run --record`` file replayed into a feed.

See ``docs/monitor.md``.
"""

from __future__ import annotations

import importlib.util

INSTALL_HINT = "the monitor needs its optional extra: pip install 'roomba-bt[monitor]'"


def server_available() -> bool:
    """True when the web server's library (aiohttp) is installed."""
    return importlib.util.find_spec("aiohttp") is not None
