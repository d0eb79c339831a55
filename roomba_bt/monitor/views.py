"""What the page is sent: plain JSON built from the feed's records, in the server's thread.

Nothing here runs on the tick path; a record's snapshot is immutable, so reading it later is
safe. Lengths are millimetres, angles radians, times seconds of mission time.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping
from typing import TYPE_CHECKING, Any

from roomba_bt.monitor.board_text import board_text
from roomba_bt.monitor.feed import TEXT_KEYS, Ending, RunFeed, TickRecord
from roomba_bt.oi.bits import ChargingState
from roomba_bt.oi.frames import (
    BATTERY_PACKETS,
    BUMPS_PACKETS,
    CHARGING_SOURCES_PACKETS,
    CHARGING_STATE_PACKETS,
    CLIFF_PACKETS,
    IR_PACKETS,
    LIGHT_BUMP_SIGNAL_PACKETS,
    LIGHT_BUMPER_PACKETS,
    REQUESTED_DRIVE_PACKETS,
    REQUESTED_WHEELS_PACKETS,
    SLOT_SECONDS,
    SensorFrame,
)
from roomba_bt.oi.ir import IRCharacter
from roomba_bt.oi.modes import DRIVING_MODES, OIMode
from roomba_bt.oi.odometry import counts_to_mm, encoder_delta
from roomba_bt.oi.opcodes import COMMANDS
from roomba_bt.oi.packets import PACKETS
from roomba_bt.printable import shortened
from roomba_bt.robot.interface import Snapshot
from roomba_bt.runtime.recording import utc_stamp

if TYPE_CHECKING:
    from roomba_bt.monitor.session import MonitorSession

#: How the page's streamed-packets table names each packet: the OI packet table's name (what
#: a mission's ``sensor:`` and a plugin read it by), title and unit, by id. Sent once, in the
#: header, so that each update carries only the frame's ids and values
#: (:func:`streamed_view`): a page keeps no list of its own.
PACKET_NAMES: dict[str, dict[str, str]] = {
    str(spec.id): {"name": spec.name, "title": spec.title, "unit": spec.unit}
    for spec in PACKETS.values()
}


def _ir(code: int) -> dict[str, Any]:
    ir = IRCharacter.decode(code)
    return {
        "code": code,
        "red_buoy": ir.red_buoy,
        "green_buoy": ir.green_buoy,
        "force_field": ir.force_field,
        "virtual_wall": ir.virtual_wall,
    }


#: packet 14's motor bits and the brushes' currents (packets 56, 57), as the page names them
OVERCURRENT_NAMES = ("main_brush", "side_brush", "left_wheel", "right_wheel")
BRUSH_CURRENT_PACKETS = {"main_brush": 56, "side_brush": 57}
_MOTORS = 138  # else PWM Motors (144)
_PWM_FULL = 127


def _motor(percent: int, direction: str | None) -> dict[str, Any]:
    return {"percent": percent, "direction": direction if percent else None}


def _signed(byte: int) -> int:
    return byte - 256 if byte > 127 else byte


def motors_view(command: bytes | None, mode: OIMode, ticked: bool) -> dict[str, Any]:
    """The brushes and vacuum as the motors' standing command set them (Motors (138): on or
    off and the brushes' directions; PWM Motors (144): a duty cycle each, a negative one the
    other way), each a percent of full power; ``note`` says why the robot does not run them
    (it is in Passive: the run's pause, or a fall) or that no command set them yet. A
    built-in cycle (Clean, Spot) runs the motors itself in Passive, which no command says:
    packets 14, 56 and 57, when streamed, show what they draw."""
    out: dict[str, Any] = {"command": None, "note": ""}
    if not command:
        for name in ("main_brush", "side_brush", "vacuum"):
            out[name] = _motor(0, None)
        # said as it is: "(a built-in cycle runs its own)" was said of every paused robot,
        # though the pause ends a cycle and none ran
        if mode in DRIVING_MODES:
            out["note"] = "off: no motor command stands"
        elif not ticked:
            out["note"] = "off: paused in Passive (the pause's safe stop); no motor command stands"
        else:
            out["note"] = (
                "off: no motor command stands, and the robot is in Passive (only a built-in "
                "cycle, Clean or Spot, runs them there)"
            )
        return out
    out["command"] = f"{COMMANDS[command[0]].title} ({command[0]})"
    if command[0] == _MOTORS:
        bits = command[1]
        main = _motor(100 if bits & 0b100 else 0, "outward" if bits & 0b10000 else "inward")
        side = _motor(100 if bits & 0b1 else 0,
                      "clockwise" if bits & 0b1000 else "counter-clockwise")  # fmt: skip
        vacuum = _motor(100 if bits & 0b10 else 0, None)
    else:  # PWM Motors: main and side brush -127..127 (negative: the other way), vacuum 0..127
        main_pwm, side_pwm = _signed(command[1]), _signed(command[2])
        main = _motor(round(abs(main_pwm) * 100 / _PWM_FULL),
                      "outward" if main_pwm < 0 else "inward")  # fmt: skip
        side = _motor(round(abs(side_pwm) * 100 / _PWM_FULL),
                      "clockwise" if side_pwm < 0 else "counter-clockwise")  # fmt: skip
        vacuum = _motor(round(command[3] * 100 / _PWM_FULL), None)
    out.update(main_brush=main, side_brush=side, vacuum=vacuum)
    if mode not in DRIVING_MODES:  # Passive: the OI runs no motor command there
        for name in ("main_brush", "side_brush", "vacuum"):
            out[name] = _motor(0, None)
        out["note"] = (
            "off while paused (the pause's safe stop); resume sends it again"
            if not ticked
            else "off: the robot is in Passive"
        )
    return out


def _motor_packets(frame: SensorFrame) -> dict[str, Any]:
    """What the robot reports of its motors, where the stream carries it: the overcurrent
    bits (packet 14) and the brushes' currents (56, 57)."""
    out: dict[str, Any] = {}
    if 14 in frame:
        over = frame.overcurrents
        out["overcurrents"] = {name: getattr(over, name) for name in OVERCURRENT_NAMES}
    for name, pid in BRUSH_CURRENT_PACKETS.items():
        if pid in frame:
            out.setdefault("brush_currents_ma", {})[name] = frame[pid]
    return out


def robot_view(snapshot: Snapshot, rates: tuple[float, float] | None) -> dict[str, Any]:
    """The robot panel: whatever the streamed frame carries, and the command rates."""
    frame = snapshot.frame
    out: dict[str, Any] = {"mode": snapshot.mode.label, "frames_lost": snapshot.frames_lost}
    if frame.carries(BUMPS_PACKETS):
        b = frame.bumps
        out["bumps"] = {"left": b.bump_left, "right": b.bump_right}
        out["wheel_drops"] = {"left": b.wheel_drop_left, "right": b.wheel_drop_right}
    if frame.carries(CLIFF_PACKETS):
        out["cliffs"] = {
            "left": frame.cliff_left,
            "front_left": frame.cliff_front_left,
            "front_right": frame.cliff_front_right,
            "right": frame.cliff_right,
        }
    for pid, label in zip(IR_PACKETS, ("omni", "left", "right"), strict=True):
        if pid in frame:
            out.setdefault("ir", {})[label] = _ir(int(frame[pid]))
    if frame.carries(LIGHT_BUMPER_PACKETS):
        lb = frame.light_bumper
        out["light_bumper"] = {
            "left": lb.left, "front_left": lb.front_left, "center_left": lb.center_left,
            "center_right": lb.center_right, "front_right": lb.front_right, "right": lb.right,
        }  # fmt: skip
    if frame.carries(LIGHT_BUMP_SIGNAL_PACKETS):
        out["light_bump_signals"] = list(frame.light_bump_signals)
    if frame.carries(BATTERY_PACKETS):
        out["battery_percent"] = round(frame.battery_percent, 1)
    if frame.carries(CHARGING_STATE_PACKETS):
        state = frame.value("charging_state")
        out["charging"] = (
            ChargingState(state).name.lower().replace("_", " ")
            if state in ChargingState._value2member_map_
            else f"unknown ({state})"
        )
    if frame.carries(CHARGING_SOURCES_PACKETS):
        sources = frame.charging_sources
        out["charging_sources"] = {
            "home_base": sources.home_base,
            "internal": sources.internal_charger,
        }
    if frame.carries(REQUESTED_WHEELS_PACKETS):
        out["wheels"] = {
            "left": frame.requested_left_velocity,
            "right": frame.requested_right_velocity,
            "source": f"requested {REQUESTED_WHEELS_PACKETS}",
        }
    else:
        velocity, radius = REQUESTED_DRIVE_PACKETS
        if velocity in frame:  # the radius may be missing
            out["wheels"] = {
                "velocity": frame[velocity],
                "radius": frame.get(radius),
                "source": f"requested ({velocity})",
            }
    odo = snapshot.odometry
    out["odometry"] = {"x": odo.x_mm, "y": odo.y_mm, "theta": odo.theta_rad, "path": odo.path_mm}
    if rates is not None:
        out["commands_per_s"], out["refused_per_s"] = rates
    return out


def streamed_view(frame: SensorFrame) -> dict[str, tuple[int, ...]]:
    """The page's streamed-packets table: every packet of the stream request, raw, in the
    frame's order, so that a packet a plugin reads (dirt detect, 15; wall signal, 27) that no
    row of the robot panel decodes is on the page too. The frame's own tuples of ids and
    values, nothing made a packet (the page is sent up to 20 times a second); the header's
    :data:`PACKET_NAMES` names them."""
    return {"ids": frame.packet_ids, "values": frame.values}


def _rates(record: TickRecord, earlier: list[TickRecord]) -> tuple[float, float] | None:
    """Per second of the stream (a paused run's mission time stands still; its stream not)."""
    if not earlier or earlier[0].tick >= record.tick:
        return None
    dt = (record.tick - earlier[0].tick) * SLOT_SECONDS
    return (
        round((record.sent - earlier[0].sent) / dt, 1),
        round((record.refused - earlier[0].refused) / dt, 1),
    )


def blackboard_view(
    board: Mapping[str, Any], rewound: bool, live_keys: Collection[str] = ()
) -> dict[str, str]:
    """The blackboard as shown, key by key: a value that changes in place as its text at the
    tick (the feed kept it so: its :data:`TEXT_KEYS` entry, left out here), any other as
    :func:`board_text` reads it (a record as JSON-like text, not its Python repr). A key in
    ``live_keys`` (its text too slow to take every tick: kept as the object) shows the object
    as it is now, which a rewound tick says."""
    texts = board.get(TEXT_KEYS, ())
    shown: dict[str, str] = {}
    for key, value in sorted(board.items()):
        if key == TEXT_KEYS:
            continue
        if key in texts:
            shown[key] = value
            continue
        text = board_text(value)
        shown[key] = (
            f"{text} (its value now, not at this tick)" if rewound and key in live_keys else text
        )
    return shown


def state_view(feed: RunFeed, record: TickRecord, earlier: list[TickRecord]) -> dict[str, Any]:
    """One tick: statuses, failure reasons, robot, poses, blackboard."""
    snapshot = feed.snapshot(record)
    board = feed.blackboard(record)
    newest = feed.latest()
    rewound = newest is not None and newest.seq != record.seq
    out: dict[str, Any] = {
        "seq": record.seq,
        "tick": record.tick,
        "time": round(record.time, 3),
        "tree": record.tree,
        "statuses": record.statuses,
        "changed": list(record.changed),
        "reasons": {str(k): v for k, v in record.reasons.items()},
        "ticked": record.ticked,
        "truth": list(record.truth) if record.truth is not None else None,
        "blackboard": blackboard_view(board, rewound, feed.live_keys),
    }
    if snapshot is not None:
        robot = out["robot"] = robot_view(snapshot, _rates(record, earlier))
        robot["motors"] = motors_view(record.motors, snapshot.mode, record.ticked)
        robot.update(_motor_packets(snapshot.frame))
        robot["streamed"] = streamed_view(snapshot.frame)
        if "wheels" not in robot and len(earlier) > 1:
            measured = _measured_wheels(record, earlier[1])
            if measured is not None:
                robot["wheels"] = measured
        if feed.ending is not None and not rewound:
            after_the_end(robot, feed.ending)
            out["ended"] = feed.ending.as_json()
    return out


def after_the_end(robot: dict[str, Any], ending: Ending) -> None:
    """The robot panel of a run that has ended, from its newest tick: the safe stop came
    after that tick (with the stream paused, no frame shows it), so the tick's mode, wheels
    and motors are not what the robot was left in. A stop known delivered: the final mode,
    the wheels at 0 (its drive 0, or Passive, which no drive moves), the motors off. One not
    delivered: the mode unknown, and the wheels and motors said to be the last seen."""
    robot["mode"] = ending.mode
    if ending.stopped:
        robot["wheels"] = {"left": 0, "right": 0, "source": "after the run's safe stop"}
        robot["motors"] = {"command": None, "note": "off: the run's safe stop"}
        for name in ("main_brush", "side_brush", "vacuum"):
            robot["motors"][name] = _motor(0, None)
        robot.pop("brush_currents_ma", None)  # the last frame's, drawn before the stop
        return
    # the final mode's words: a stop written to a robot asleep is "unconfirmed", not "not
    # delivered", which the panel said of it beside the banner's "unconfirmed"
    unknown = f"last seen before the end; {ending.stop_said}"
    if "wheels" in robot:
        robot["wheels"]["source"] += f"; {unknown}"
    if "motors" in robot:
        robot["motors"]["note"] = unknown


def _measured_wheels(record: TickRecord, previous: TickRecord) -> dict[str, Any] | None:
    """Wheel speeds from the encoders (43, 44) between the previous record and this one."""
    a, b = previous.odometry, record.odometry
    if a is None or b is None or record.tick <= previous.tick:
        return None
    if a.left_counts is None or a.right_counts is None:
        return None
    if b.left_counts is None or b.right_counts is None:
        return None
    dt = (record.tick - previous.tick) * SLOT_SECONDS
    left = counts_to_mm(encoder_delta(a.left_counts, b.left_counts)) / dt
    right = counts_to_mm(encoder_delta(a.right_counts, b.right_counts)) / dt
    return {"left": round(left), "right": round(right), "source": "encoders (43, 44)"}


def path_view(records: list[TickRecord]) -> dict[str, list[list[float]]]:
    odometry: list[list[float]] = []
    truth: list[list[float]] = []
    for r in records:
        if r.odometry is not None:
            odo = r.odometry
            odometry.append([round(odo.x_mm, 1), round(odo.y_mm, 1)])
        if r.truth is not None:
            truth.append([round(r.truth[0], 1), round(r.truth[1], 1)])
    return {"odometry": odometry, "truth": truth}


def tree_view(feed: RunFeed, generation: int | None = None) -> list[dict[str, Any]]:
    infos = feed.trees.get(feed.generation if generation is None else generation, [])
    return [info.as_json() for info in infos]


def session_view(session: MonitorSession | None) -> dict[str, Any]:
    """What the page shows of the operator's session: paused (why, since which tick, the
    countdown to the robot's sleep), the breakpoints and forced conditions by node index; a
    recorded run's: none of them."""
    if session is None:
        return {"paused": False, "pause_reason": "", "paused_tick": None, "sleep_note": "",
                "held_end": "", "breakpoints": {}, "forced": {}}  # fmt: skip
    state = session.state
    return {
        "paused": state.paused,
        "pause_reason": state.pause_reason,
        "paused_tick": state.paused_tick,
        "sleep_note": state.sleep_note,
        "held_end": state.held_end,
        "breakpoints": {str(k): v for k, v in state.breakpoints.items()},
        "forced": {str(k): v for k, v in state.forced.items()},
    }


def world_view(simulator: Any) -> dict[str, Any]:
    """The simulator's world as the page draws it (:func:`world_drawing`)."""
    return world_drawing(simulator.world)


def world_drawing(world: Any) -> dict[str, Any]:
    """A world as the page draws it, a live simulator's or the one a record names (the
    shapes ``sim/plot.py`` draws; a dirt patch with the dirt-detect level, packet 15, the
    robot reads over it)."""
    out: dict[str, Any] = {
        "name": getattr(world, "name", ""),
        "rooms": [[list(p) for p in room] for room in world.rooms],
        "walls": [list(w) for w in world.walls],
        "obstacles": [[list(p) for p in o] for o in world.obstacles],
        "drops": [[list(p) for p in d] for d in world.drops],
        "dirt": [{"area": [list(p) for p in d.area], "level": d.level} for d in world.dirt],
        "virtual_walls": [[vw.ax, vw.ay, vw.bx, vw.by] for vw in world.virtual_walls],
        "lighthouses": [[lh.x, lh.y, *lh.fence_segment] for lh in world.lighthouses],
        "dock": None,
    }
    dock = world.dock
    if dock is not None:
        out["dock"] = {
            "x": dock.x,
            "y": dock.y,
            "facing": dock.facing,
            "range": dock.buoy_range,
            "red": list(dock.red),
            "green": list(dock.green),
            "force_field": dock.force_field,
            "plate": list(dock.plate),
        }
    return out


def run_view(feed: RunFeed) -> dict[str, str]:
    """Which run this is: its id (a page loaded for another refuses to take it silently, and
    sends it with each control), its mission, its robot, when it started (ISO 8601, UTC;
    empty when unknown: a record made before its header held it) and its label (``run
    --label``; empty for none). The mission's name and the label are cut as a terminal's
    line cuts them (:func:`~roomba_bt.printable.shortened`): a record's header or a
    mission's ``mission:`` may hold 10 MB, which became the page's title and header."""
    return {
        "id": feed.run_id,
        "mission": shortened(feed.mission_name),
        "robot": shortened(feed.robot),
        "started": utc_stamp(feed.started) if feed.started is not None else "",
        "label": shortened(feed.label),
    }


def header_view(feed: RunFeed, extra: Mapping[str, Any]) -> dict[str, Any]:
    first, last = feed.window()
    run = run_view(feed)
    return {
        "run": run,
        "mission": run["mission"],
        "source": feed.source,
        "generation": feed.generation,
        "tree": tree_view(feed),
        "world": feed.world,
        "first_tick": first.tick if first else 0,
        "last_tick": last.tick if last else 0,
        "finished": feed.finished,
        "no_end": feed.no_end,
        "truth_start": list(feed.truth_start) if feed.truth_start is not None else None,
        "packets": PACKET_NAMES,
        **extra,
    }
