"""Power: the battery, the currents that drain it, and charging on the dock's contacts.

When not charging, the battery gives 150 mA for the robot itself, 0.6 mA per mm/s of each
wheel and 1.6 mA per PWM step of each brush and the vacuum (a stalled wheel's own current,
packets 54 and 55, is 600 mA higher). On a powered dock in Passive or Off it charges at
1500 mA, at 150 mA once 98 % full. Reported in packets 21 (charging state), 22 (voltage),
23 (current), 25 (charge), 26 (capacity), 34 (charging sources: home base), 54-57 (motor
currents) and 14 (overcurrents).

A layer of the simulator (see state.py): the charge integrates on every step, so its state is
on the robot; the currents are recomputed only when what draws them changes.
"""

from __future__ import annotations

import struct

from roomba_bt.oi.modes import OIMode
from roomba_bt.sim.motion import Motion

BATTERY_CAPACITY_MAH = 2696.0


class Power(Motion):
    """Battery charge and currents; the brushes and vacuum, which draw current too."""

    def _init_power(self) -> None:
        self.battery_charge = self.world.battery * BATTERY_CAPACITY_MAH
        self.motor_bits = 0
        self.brush_pwm = (0, 0, 0)
        self._current = 0.0
        #: what the currents were computed for (None: compute them again)
        self._power_key: tuple[object, ...] | None = None
        v = self.values
        v[26] = int(BATTERY_CAPACITY_MAH)
        v[24] = 24  # temperature, deg C

    @property
    def charging(self) -> bool:
        return self.values[21] in (1, 2, 3)

    def _on_motors(self, args: bytes) -> None:
        self.motor_bits = args[0]
        self.brush_pwm = (
            127 if args[0] & 4 else 0,
            127 if args[0] & 1 else 0,
            127 if args[0] & 2 else 0,
        )

    def _on_pwm_motors(self, args: bytes) -> None:
        main, side, vacuum = struct.unpack(">bbb", args)
        self.brush_pwm = (main, side, vacuum)
        self.motor_bits = (1 if side else 0) | (2 if vacuum else 0) | (4 if main else 0)

    def _battery(self, dt: float) -> None:
        """Charge and currents. Currents are recomputed only when what draws them changes
        (the step must stay cheap); the charge integrates every step."""
        key = (
            self.left_speed, self.right_speed, self.brush_pwm, self.docked, self.dock_powered,
            self.mode, self.blocked, self._stall_steps > 30,
        )  # fmt: skip
        if key != self._power_key:
            self._power_key = key
            self._power_changed()
        charge = self.battery_charge + self._current * dt / 3600.0
        if charge >= BATTERY_CAPACITY_MAH * 0.98 and self._current > 200.0:
            self._power_key = None  # switch to trickle charging
        if charge < 0.0:
            charge = 0.0
        elif charge > BATTERY_CAPACITY_MAH:
            charge = BATTERY_CAPACITY_MAH
        self.battery_charge = charge
        if not self.ticks & 31:
            self._update_battery_values()

    def _power_changed(self) -> None:
        v = self.values
        charging = self.docked and self.dock_powered and self.mode in (OIMode.PASSIVE, OIMode.OFF)
        if charging:
            full = self.battery_charge >= BATTERY_CAPACITY_MAH * 0.98
            current = 150.0 if full else 1500.0
            v[21] = 3 if full else 2
        else:
            wheels = abs(self.left_speed) + abs(self.right_speed)
            brushes = abs(self.brush_pwm[0]) + abs(self.brush_pwm[1]) + abs(self.brush_pwm[2])
            current = -(150.0 + 0.6 * wheels + 1.6 * brushes)
            v[21] = 0
        self._current = current
        v[34] = 2 if self.docked and self.dock_powered else 0
        stall = 600 if self.blocked else 0
        left, right = self.left_speed, self.right_speed
        v[54] = int(0.6 * left) + (stall if left > 0 else -stall if left < 0 else 0)
        v[55] = int(0.6 * right) + (stall if right > 0 else -stall if right < 0 else 0)
        v[56] = int(2.4 * abs(self.brush_pwm[0]))
        v[57] = int(0.8 * abs(self.brush_pwm[1]))
        over = 0
        if self._stall_steps > 30:
            over |= (16 if left else 0) | (8 if right else 0)
        v[14] = over
        self._update_battery_values()

    def _update_battery_values(self) -> None:
        v = self.values
        fraction = self.battery_charge / BATTERY_CAPACITY_MAH
        v[25] = int(self.battery_charge)
        v[22] = int(13200 + 3200 * fraction + (600 if self._current > 0 else 0))
        v[23] = int(self._current)
