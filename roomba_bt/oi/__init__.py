"""The Open Interface protocol: tables, encoder, decoder, stream parser. Pure: no I/O.

Standard library only. Everything above (transport, robot, simulator, missions) reads the
tables defined here: :mod:`~roomba_bt.oi.opcodes` and :mod:`~roomba_bt.oi.packets`.

``roomba_bt.oi.encode`` is the encoder's module, as ``import roomba_bt.oi.encode`` says, and
its function is ``roomba_bt.oi.encode.encode`` (``commands.encode``). The package once
exported the function under the module's name, so the module, once imported, was out of
reach by its own path (``import roomba_bt.oi.encode as e`` gave the function, which has no
``drive``): nothing here takes a submodule's name.

``commands`` is the encoder's name for plugin authors, a name of this package: ``from
roomba_bt.oi import commands`` (docs/plugins.md). As a module path (``import
roomba_bt.oi.commands``, ``from roomba_bt.oi.commands import drive``) it still gives the one
module, with a DeprecationWarning until 0.3.0 (:mod:`roomba_bt.oi.commands`).
"""

from roomba_bt.oi import encode as commands
from roomba_bt.oi.bits import (
    BumpsWheelDrops,
    Buttons,
    ChargingSources,
    ChargingState,
    LightBumper,
    Overcurrents,
    Stasis,
)
from roomba_bt.oi.encode import Command, Note, Radius, decode_command
from roomba_bt.oi.errors import BandwidthError, EncodeError, OIError, UnsupportedCommandError
from roomba_bt.oi.frames import FrameLayout, SensorFrame, layout_for, stream_frame_size
from roomba_bt.oi.ir import IRCharacter, IRSource, LighthouseBeam
from roomba_bt.oi.modes import OIMode, mode_from_packet
from roomba_bt.oi.opcodes import COMMANDS, COMMANDS_BY_NAME, ArgSpec, CommandSpec, TailSpec
from roomba_bt.oi.packets import GROUP_SIZES, GROUPS, PACKETS, PACKETS_BY_NAME, PacketSpec
from roomba_bt.oi.profiles import PROFILES, RobotProfile, command_warning, get_profile
from roomba_bt.oi.stream import (
    ReplyParser,
    StreamParser,
    check_bandwidth,
    decode_reply,
    stream_budget,
)

__all__ = [
    "COMMANDS",
    "COMMANDS_BY_NAME",
    "GROUPS",
    "GROUP_SIZES",
    "PACKETS",
    "PACKETS_BY_NAME",
    "PROFILES",
    "ArgSpec",
    "BandwidthError",
    "BumpsWheelDrops",
    "Buttons",
    "ChargingSources",
    "ChargingState",
    "Command",
    "CommandSpec",
    "EncodeError",
    "FrameLayout",
    "IRCharacter",
    "IRSource",
    "LightBumper",
    "LighthouseBeam",
    "Note",
    "OIError",
    "OIMode",
    "Overcurrents",
    "PacketSpec",
    "Radius",
    "ReplyParser",
    "RobotProfile",
    "SensorFrame",
    "Stasis",
    "StreamParser",
    "TailSpec",
    "UnsupportedCommandError",
    "check_bandwidth",
    "command_warning",
    "commands",
    "decode_command",
    "decode_reply",
    "get_profile",
    "layout_for",
    "mode_from_packet",
    "stream_budget",
    "stream_frame_size",
]
