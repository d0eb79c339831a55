"""Power: the battery, the currents that drain it, and charging on the dock's contacts.

When not charging, the battery gives 150 mA for the robot itself, 0.6 mA per mm/s of each
wheel and each cleaning motor's own current, in proportion to its duty cycle (0..127 of PWM
Motors 144; Motors 138 runs one at 127): the main brush 2.4 mA a step (packet 56, about
300 mA at full power), the side brush 0.8 mA (packet 57, about 100 mA), the vacuum 1.6 mA
(in no packet; about 200 mA). A stalled wheel's own current, packets 54 and 55, is 600 mA
higher. On a powered dock, or with the wall charger plugged
in (a world's ``plug`` event), in Passive or Off it charges at 1500 mA, at 150 mA once 98 %
full. Reported in packets 21 (charging state), 22 (voltage), 23 (current), 25 (charge), 26
(capacity), 34 (charging sources: home base, internal charger), 54-57 (motor
currents) and 14 (overcurrents).

A layer of the simulator (see state.py). The charge integrates on every step, and the
currents are recomputed only when what draws them changes; the packets show the charge every
32nd step (about 0.5 s) and when the currents change. So the battery's step
(:meth:`Power._battery`) runs only then: on a step after something the currents depend on
changed (the wheel speeds, brushes, dock, mode, a stall: every place that changes one sets
``_power_due``), on every 32nd step, and on every step while charging fast (its switch to
trickle charging is checked every step). On the other steps the robot's ``step`` only counts
the charge's step as owed (``_charge_owed``); the owed steps are taken, one by one as
:meth:`Power._battery` takes them, the next time the battery's step runs or the charge is
read (:attr:`Power.battery_charge`). The same additions, in the same order: the same charge
and packets, for a count a step instead of a call and a comparison of what draws the
currents (tests/sim/test_physics.py checks both, and that no change is missed)::

    step        1   2 ... 31  32  33 ... 40  41 ...   (the wheels change speed at step 40)
    _battery    x             x              x  x ...  the charge of steps 33-39 owed, taken
    owed        1   2 ... 31  0   1  ... 7   0  0      at 40 before the currents change
"""

from __future__ import annotations

import struct
from math import trunc

from roomba_bt.oi.modes import OIMode
from roomba_bt.sim.motion import Motion
from roomba_bt.sim.state import STEP_SECONDS

BATTERY_CAPACITY_MAH = 2696.0
#: each cleaning motor's current (mA) per step of its duty cycle, as packets 56 and 57 report
#: the brushes' and the battery gives all three: the main brush, the side brush, the vacuum
#: (until 0.2.0 the battery gave 1.6 mA a step of each, less than packet 56 said the main
#: brush alone drew when it ran without the side brush)
MOTOR_MA_PER_STEP = (2.4, 0.8, 1.6)
#: above this current (mA, charging fast) the battery's step runs every step (trickle switch)
_FAST_CHARGE_MA = 200.0
#: 1 mAh below the capacity (:meth:`Power._settle_charge`)
_NEAR_FULL = BATTERY_CAPACITY_MAH - 1.0


class Power(Motion):
    """Battery charge and currents; the brushes and vacuum, which draw current too."""

    #: its own state's attributes (state.py: slots, not a dict, on the step's path)
    __slots__ = (
        "_battery_at", "_charge", "_charge_owed", "_current", "_power_key", "brush_pwm",
        "motor_bits",
    )  # fmt: skip

    def _init_power(self) -> None:
        #: the charge (mAh) as of the last battery step, and the steps since whose charge is
        #: owed (:attr:`battery_charge` is the charge now)
        self._charge = self.world.battery * BATTERY_CAPACITY_MAH
        self._charge_owed = 0
        #: the step the battery's step next runs at unless something changes first
        self._battery_at = 0
        self.motor_bits = 0
        self.brush_pwm = (0, 0, 0)
        self._current = 0.0
        #: what the currents were computed for (None: compute them again)
        self._power_key: tuple[object, ...] | None = None
        v = self.values
        v[26] = int(BATTERY_CAPACITY_MAH)
        v[24] = 24  # temperature, deg C

    @property
    def battery_charge(self) -> float:
        """The charge now (mAh), the steps owed taken."""
        if self._charge_owed:
            self._settle_charge()
        return self._charge

    @battery_charge.setter
    def battery_charge(self, charge: float) -> None:
        self._charge_owed = 0  # what the owed steps would have added is replaced
        self._charge = charge

    @property
    def charging(self) -> bool:
        return self.values[21] in (1, 2, 3)

    def _on_motors(self, args: bytes) -> None:
        self._power_due = True
        self.motor_bits = args[0]
        self.brush_pwm = (
            127 if args[0] & 4 else 0,
            127 if args[0] & 1 else 0,
            127 if args[0] & 2 else 0,
        )

    def _on_pwm_motors(self, args: bytes) -> None:
        main, side, vacuum = struct.unpack(">bbb", args)
        self._power_due = True
        self.brush_pwm = (main, side, vacuum)
        self.motor_bits = (1 if side else 0) | (2 if vacuum else 0) | (4 if main else 0)

    def _battery(self, dt: float) -> None:
        """The battery's step: the owed steps' charge, the currents if what draws them
        changed, this step's charge, the packets every 32nd step. Runs when due (see the
        module's docstring); ``dt`` is this step's length."""
        if self._charge_owed:
            self._settle_charge()
        self._power_due = False
        key = self._power_inputs()
        if key != self._power_key:
            self._power_key = key
            self._power_changed()
        current = self._current
        charge = self._charge + current * dt / 3600.0
        if charge >= BATTERY_CAPACITY_MAH * 0.98 and current > _FAST_CHARGE_MA:
            self._power_key = None  # switch to trickle charging on the next step
        if charge < 0.0:
            charge = 0.0
        elif charge > BATTERY_CAPACITY_MAH:
            charge = BATTERY_CAPACITY_MAH
        self._charge = charge
        ticks = self.ticks
        if not ticks & 31:
            self._update_battery_values()
        self._battery_at = ticks + 1 if current > _FAST_CHARGE_MA else (ticks | 31) + 1

    def _settle_charge(self) -> None:
        """The owed steps' charge, each step's as :meth:`_battery` adds it (a 15 ms step:
        the robot's ``step`` owes only those; the current the same all along, below
        _FAST_CHARGE_MA)."""
        added = self._current * STEP_SECONDS / 3600.0
        charge = self._charge
        owed = self._charge_owed
        if 0.0 <= charge <= BATTERY_CAPACITY_MAH and 1.0 < charge + owed * added < _NEAR_FULL:
            # The sums go one way, from a charge within the limits to one over 1 mAh inside
            # them (rounding is far less): no step reaches a limit, none is checked.
            for _ in range(owed):
                charge += added
        else:
            for _ in range(owed):
                charge = charge + added
                if charge < 0.0:
                    charge = 0.0
                elif charge > BATTERY_CAPACITY_MAH:
                    charge = BATTERY_CAPACITY_MAH
        self._charge = charge
        self._charge_owed = 0

    def _power_inputs(self) -> tuple[object, ...]:
        """What the currents are computed from (:meth:`_power_changed`) and may change from
        step to step. The world's timeline's effects (the dock's power, the wall charger's
        plug, an overcurrent event) are left out: they change only when an event starts or
        ends, and :meth:`_timeline_changed_power` drops the key then, so a world without
        events does not pay for reading and comparing them on every battery step."""
        return (
            self.left_speed, self.right_speed, self.brush_pwm, self.docked, self.mode,
            self.blocked, self._stall_steps > 30,
        )  # fmt: skip

    def _timeline_changed_power(self) -> None:
        """An event started or ended (robot.py's ``_world_events``): the currents are
        computed again on the next step, whatever the key (:meth:`_power_inputs`)."""
        self._power_key = None
        self._power_due = True

    def _power_changed(self) -> None:
        v = self.values
        on_dock = self.docked and self.dock_powered
        charging = (on_dock or self.plugged_in) and self.mode in (OIMode.PASSIVE, OIMode.OFF)
        if charging:
            full = self._charge >= BATTERY_CAPACITY_MAH * 0.98
            current = 150.0 if full else 1500.0
            v[21] = 3 if full else 2
        else:
            wheels = abs(self.left_speed) + abs(self.right_speed)
            main, side, vacuum = self.brush_pwm
            per_main, per_side, per_vacuum = MOTOR_MA_PER_STEP
            brushes = per_main * abs(main) + per_side * abs(side) + per_vacuum * abs(vacuum)
            current = -(150.0 + 0.6 * wheels + brushes)
            v[21] = 0
        self._current = current
        v[34] = (2 if on_dock else 0) | (1 if self.plugged_in else 0)  # home base, internal
        stall = 600 if self.blocked else 0
        left, right = self.left_speed, self.right_speed
        v[54] = trunc(0.6 * left) + (stall if left > 0 else -stall if left < 0 else 0)
        v[55] = trunc(0.6 * right) + (stall if right > 0 else -stall if right < 0 else 0)
        v[56] = trunc(MOTOR_MA_PER_STEP[0] * abs(self.brush_pwm[0]))
        v[57] = trunc(MOTOR_MA_PER_STEP[1] * abs(self.brush_pwm[1]))
        over = 0
        if self._stall_steps > 30:
            over |= (16 if left else 0) | (8 if right else 0)
        v[14] = over | self._event_overcurrents  # a world's overcurrent event: a tangled brush
        self._update_battery_values()

    def _update_battery_values(self) -> None:
        v = self.values
        fraction = self._charge / BATTERY_CAPACITY_MAH
        v[25] = trunc(self._charge)
        v[22] = trunc(13200 + 3200 * fraction + (600 if self._current > 0 else 0))
        v[23] = trunc(self._current)
