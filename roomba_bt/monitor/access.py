"""Who may do what on the monitor's page: the control token and the view token.

A teacher shows a run on a projector, or shares a link with a class, without handing over
the robot: anyone with the page's one token could pause, step, force conditions and stop
it. So where a token is in force there are two: the control token (the one printed first,
or ``--monitor-token``) opens the page with its controls; the view token (printed on the
``view only`` line, or ``--monitor-view-token``) opens the same page, the same state and the
same live updates, and nothing else: its controls are off and ``POST /api/control`` answers
403. Without a token in force (a loopback address with neither chosen) every request is the
controlling one, as before.
"""

from __future__ import annotations

import hmac
import secrets
from dataclasses import dataclass
from enum import Enum

from roomba_bt.monitor.address import is_loopback

#: why a view token may not be the control token
SAME_TOKEN = "the view token is the control token: a viewer would have the controls"


class Access(Enum):
    """What a request's token lets it do."""

    CONTROL = "control"
    VIEW = "view"


def new_token() -> str:
    """A token nobody can guess: 144 random bits, URL-safe (24 characters)."""
    return secrets.token_urlsafe(18)


@dataclass(frozen=True)
class Tokens:
    """The tokens a monitor server accepts; ``control`` None: no token in force (loopback)."""

    control: str | None
    view: str | None

    @classmethod
    def make(
        cls,
        host: str,
        *,
        has_controls: bool,
        control: str | None = None,
        view: str | None = None,
    ) -> Tokens:
        """The tokens of a server on ``host``: the chosen ones, else new ones where needed.

        A control token is in force on a non-loopback address, or when one is chosen, or when
        a view token is chosen (a view token alone would guard nothing: on loopback without
        a token everyone has the controls). A view token is made when a control token is in
        force and the page has controls to withhold (not ``--monitor-readonly``, not a
        recorded run); a chosen one is kept either way, so its bookmark opens the page."""
        if control is None and (view is not None or not is_loopback(host)):
            control = new_token()
        if view is None and control is not None and has_controls:
            view = new_token()
        if control is not None and view is not None and _same(control, view):
            raise ValueError(SAME_TOKEN)
        return cls(control, view)

    def access(self, given: str) -> Access | None:
        """What ``given`` (a request's token) may do, or None when it is neither token. Each
        token is compared in constant time, both always, so the time taken says nothing of
        either."""
        is_control = self.control is not None and _same(given, self.control)
        is_view = self.view is not None and _same(given, self.view)
        if is_control:
            return Access.CONTROL
        return Access.VIEW if is_view else None


def _same(given: str, token: str) -> bool:
    return hmac.compare_digest(given.encode(), token.encode())
