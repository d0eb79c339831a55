"""How a mission's messages name what its caller gives it: the command line's flags, or the
arguments of a Python call.

A message about something only the caller can change (a permission, a parameter's value, the
robot's profile) says how to change it. The command line's user changes it with a flag
(``--allow-plugin-files``, ``-p speed=250mm/s``); a program calling ``load_mission`` with an
argument (``permissions=Permissions(plugin_files=True)``, ``params={"speed": "250mm/s"}``),
and a flag it cannot give was no help to it. The caller's :class:`Wording` travels with what
it grants (:attr:`Permissions.wording <roomba_bt.mission.loader.Permissions.wording>`):
:data:`PYTHON` unless the command line says :data:`COMMAND_LINE`.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, slots=True, repr=False)
class Wording:
    """What the caller writes to change each thing a message may name."""

    #: the module's name for it (its repr: a signature's default reads ``PYTHON``, not the
    #: whole table)
    name: str

    #: what lets a mission import the plugin files it names
    allow_plugin_files: str
    #: what lets a mission include from another folder (``DIR``)
    include_dir: str
    #: where a value the caller set came from, after the value: "set on the command line"
    set_by: str
    #: the same in a parenthesis after the value: "(from the command line)"
    set_from: str
    #: how the caller sets parameter ``{name}`` to ``{value}``
    give_template: str
    #: how a parameter's value is set instead of a default that refers to another
    set_instead: str
    #: how the caller chooses the robot's profile
    profile: str
    #: how to run a mission on the world file ``{path}``
    on_world: str
    #: how to see the shipped world ``{name}``, given where a mission was asked for, and
    #: run a mission in it (:func:`~roomba_bt.mission.shipped.a_world_s_name`)
    on_world_name: str
    #: how the caller lists the shipped missions ("" when it has no such command)
    lists_missions: str
    #: how the caller leaves the robot in Off (Stop, 173) at the end of a mission
    end_in_stop: str
    #: the parameters the caller gave somewhere more particular than :attr:`set_by` says,
    #: each with where: ``eval --variant`` (``("speed", "--variant 'speed=fast'")``), so
    #: that of ten variants the message names the one with the bad value
    origins: tuple[tuple[str, str], ...] = ()

    def __repr__(self) -> str:
        return f"roomba_bt.mission.wording.{self.name}"

    def set_by_for(self, name: str) -> str:
        """:attr:`set_by` for parameter ``name``: ``set by --variant 'speed=fast'`` when
        :attr:`origins` names where it came from."""
        origin = dict(self.origins).get(name)
        return self.set_by if origin is None else f"set by {origin}"

    def set_from_for(self, name: str) -> str:
        """:attr:`set_from` for parameter ``name``: ``from --variant 'speed=fast'``."""
        origin = dict(self.origins).get(name)
        return self.set_from if origin is None else f"from {origin}"

    def give(self, assignment: str) -> str:
        """``"creep=VALUE"`` as the caller gives it: ``-p creep=VALUE``,
        ``params={'creep': 'VALUE'}``."""
        name, _, value = assignment.partition("=")
        return self.give_template.format(name=name, value=value)


#: A Python program's words: ``load_mission``'s and ``compile_mission``'s arguments.
PYTHON = Wording(
    name="PYTHON",
    allow_plugin_files="permissions=Permissions(plugin_files=True)",
    include_dir="permissions=Permissions(include_dirs=(Path('DIR'),))",
    set_by="given in params",
    set_from="given in params",
    give_template="params={{'{name}': '{value}'}}",
    set_instead="params= sets it when the mission is loaded",
    profile="profile= (roomba_bt.PROFILES)",
    on_world="load_world({path!r}) and a Simulator on it",
    on_world_name="load_world({name!r}) loads it, a Simulator on it runs a mission in it",
    lists_missions="",
    end_in_stop="end_in='stop' (RunStack's or Connection's)",
)

#: The ``roomba-bt`` command's words: its flags.
COMMAND_LINE = Wording(
    name="COMMAND_LINE",
    allow_plugin_files="--allow-plugin-files",
    include_dir="--include-dir DIR",
    set_by="set on the command line",
    set_from="from the command line",
    give_template="-p {name}={value}",
    set_instead="-p sets it on the command line",
    profile="--profile",
    on_world=(
        "--world {path} (roomba-bt run dock --world {path} --fast); roomba-bt validate {path} "
        "checks it"
    ),
    on_world_name=(
        "`roomba-bt worlds {name}` shows it, `roomba-bt run MISSION --world {name}` runs a "
        "mission in it"
    ),
    lists_missions="; `roomba-bt missions` lists them",
    end_in_stop="--end-in stop",
)
