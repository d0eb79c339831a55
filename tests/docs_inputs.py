"""The files that make the diagnostics docs/missions.md quotes (``m.yaml:9:25: drive: ...``),
each written so that ``roomba-bt validate`` says the quoted line at the quoted line and
column: the page shows the message, not the mission, so the test writes one
(tests/test_docs_run.py's ``QUOTED``, run in the page's scratch folder).

:data:`MISSIONS_MD`: (how the quote begins, ``validate``'s arguments, its exit code, the
files). The quotes of 10,000 errors or warnings, and of a project file's grant, are held by
the tests that already make them (tests/mission/test_hostile_files.py,
tests/mission/test_include_path.py).

Three texts are the tests' own: NUDGE is tests/mission/test_subtree_uses.py's with its use
added, OWN_KEY the mission tests/mission/test_own_keys_passed.py reads, EDGE the world
tests/cli/test_validate_world.py warns of (an edit of any moves the page's quote: this test
then says so). ROUTE is written apart: the page's patrol turns 9000 deg,
test_list_parameters.py's waypoints do not."""

from __future__ import annotations

from pathlib import Path

from cli.test_validate_world import world_starting_at  # its room with stairs
from mission.team_repo import ESCAPES, SAFE_DRIVE, TO_KITCHEN  # docs/ci.md's repository
from mission.test_subtree_uses import NUDGE as SUBTREE_NUDGE  # its nudge, not yet used

Files = tuple[tuple[str, str | None], ...]

#: a song's notes written one a line, the third a German name (tests/mission/
#: test_stranger_files.py's)
NOTES = """\
mission: m
tree:
  sequence:
    - mode: safe
    - song:
        number: 0
        notes:
          - C4 250ms
          - E4 250ms
          - H4 250ms
          - G4 1s
"""

#: a list parameter's default whose second item turns 9000 deg
ROUTE = """\
parameters:
  route:
    type: list
    items: {fields: {distance: distance, turn: angle}}
    default: [{distance: 3m, turn: 90deg}, {distance: 20cm, turn: 9000deg}]
blackboard:
  wp: {fields: {distance: distance, turn: angle}}
tree:
  sequence:
    - mode: safe
    - for_each:
        key: wp
        in: "${route}"
        do: {turn: "@wp.turn"}
"""

#: ``selected:`` picking a child whose name is made with a parameter
SELECTED = """\
parameters:
  side: {type: enum, choices: [left, right], default: left}
tree:
  parallel:
    policy: selected
    selected: ["w left"]
    children:
      - {wait: 10ms, name: "w ${side}"}
      - {wait: 20ms, name: fixed}
"""

#: a subtree's drive given 900 mm/s at its second use
GIVEN = """\
mission: m
subtrees:
  go:
   parameters: {speed: {type: speed}}
   tree:
    sequence:
    - wait: 10ms
    - wait: 10ms
    - drive: {velocity: "${speed}", distance: 10cm}
tree:
  sequence:
    - mode: safe
    - subtree: {id: go, speed: 200 mm/s}
    - wait: 10ms
    - subtree: {id: go, speed: 900 mm/s}
"""

#: a subtree's own key passed down and read before anything writes it
#: (tests/mission/test_own_keys_passed.py's)
OWN_KEY = """\
mission: early
subtrees:
  measure:
    parameters: {out: {type: str}}
    tree: {check: {key: "${out}", value: 1}}
  leg:
    blackboard: {n: int}
    tree:
      sequence: [{subtree: {id: measure, out: n}}, {set: {key: n, value: 1}}]
tree: {subtree: leg}
"""

#: a step after a drive that never ends, in a subtree of the mission's own file
NUDGE = SUBTREE_NUDGE + "    - subtree: nudge\n"

#: a turn at a speed no wheel turns at, from a parameter's default
PATROL_SLOW = (
    "mission: patrol-slow\n"
    "description: Up and down the hall, slowly round at the end.\n"
    "parameters:\n"
    "  side: {type: distance, default: 1 m}\n"
    "  speed: {type: speed, default: 200 mm/s}\n"
    "  turn: {type: angle, default: 90 deg}\n"
    "  creep: {type: speed, default: 10 mm/s}\n"
    "tree:\n"
    "  sequence:\n"
    "    - mode: safe\n"
    + '    - drive: {velocity: "${speed}", distance: "${side}"}\n    - turn: "${turn}"\n' * 7
    + "    - wait: 1s\n"
    + "    - sequence:\n"
    '        - turn: {angle: 180 deg, speed: "${creep}"}\n'
    '        - drive: {velocity: "${speed}", distance: "${side}"}\n'
)

#: 0.1.0's dollars: ``$${price}`` and ``$$5``
DOLLARS = """\
mission: m
parameters:
  price: {type: int, default: 5}
tree:
  sequence:
  - mode: safe
  - wait: 10ms
  - wait: 10ms
  - log: {message: "$${price}"}
  - log: "price: $$5"
"""

#: a ``${`` that starts no parameter
BRACE = """\
mission: m
tree:
  sequence:
    - mode: safe
    - wait: 10ms
    - wait: 10ms
    - log: "cost ${ x"
"""

#: a library's drive reached in Passive through the mission's use
RECOVERY = (
    "# Recovery subtrees shared by the team's missions.\n"
    "subtrees:\n"
    "  back_off:\n"
    "    doc: Back away from what the bumper met.\n"
    "    tree:\n"
    "      sequence:\n"
    "        - drive: {velocity: -100 mm/s, distance: 5cm}\n"
    "        - turn: 45deg\n" + "        - wait: 100ms\n" * 18 + "  drive_leg:\n"
    "    doc: One leg of a patrol, a metre ahead.\n"
    "    tree:\n"
    "      drive: {velocity: 200 mm/s, distance: 1 m}\n"
)
BP_REACTIVE = """\
mission: bp_reactive
include: [../common/lib/recovery.yaml]
tree:
  sequence:
    - wait: 1s
    - wait: 1s
    - subtree: drive_leg
"""

#: a library's display given a text too long for it at the use (a Roomba 500's display)
WARNS = """\
# Subtrees that show things on the Roomba 500's four-digit display.
subtrees:
  show_text:
   doc: Show a text of at most four characters.
   parameters:
     t: {type: str, default: "OK"}
   # said on the display, as it is
   tree: {display: "${t}"}
"""
WARNUSE = """\
mission: warnuse
include: [../common/lib/warns.yaml]
# the text is a parameter of the subtree
tree:
  sequence:
    - mode: safe
    - subtree: {id: show_text, t: TOOLONG}
"""

#: docs/ci.md's repository (tests/mission/team_repo.py), its library broken
TEAM: Files = (
    ("missions/common/lib/escapes.yaml", ESCAPES),
    ("missions/common/lib/safe_drive.yaml", SAFE_DRIVE),
    ("missions/delivery/to-kitchen.yaml", TO_KITCHEN),
)

MISSIONS_MD: list[tuple[str, str, int, Files]] = [
    ("m.yaml:10:13: song.notes:", "m.yaml", 2, (("m.yaml", NOTES),)),
    ("m.yaml:5:44: for_each item", "m.yaml", 2, (("m.yaml", ROUTE),)),
    ("m.yaml:8:28: parallel.selected", "m.yaml", 2, (("m.yaml", SELECTED),)),
    ("m.yaml:9:25: drive:", "m.yaml", 2, (("m.yaml", GIVEN),)),
    ("m.yaml:9:19: subtree measure", "m.yaml", 2, (("m.yaml", OWN_KEY),)),
    ("m.yaml:8:11: warning: log(after)", "m.yaml", 0, (("m.yaml", NUDGE),)),
    ("patrol-slow.yaml:27:41:", "patrol-slow.yaml", 2, (("patrol-slow.yaml", PATROL_SLOW),)),
    ("m.yaml:9:21: warning:", "m.yaml", 0, (("m.yaml", DOLLARS),)),
    ("m.yaml:10:18: warning:", "m.yaml", 0, (("m.yaml", DOLLARS),)),
    ("m.yaml:7:12: log.message:", "m.yaml", 2, (("m.yaml", BRACE),)),
    ("missions/common/lib/escapes.yaml:7:50:",
     "--include-dir missions/common missions/delivery/to-kitchen.yaml", 2, TEAM),
    ("missions/bp_reactive.yaml:7:7:", "--include-dir common missions/bp_reactive.yaml", 2,
     (("common/lib/recovery.yaml", RECOVERY), ("missions/bp_reactive.yaml", BP_REACTIVE))),
    ("missions/warnuse.yaml:7:7:",
     "--profile roomba500 --include-dir common missions/warnuse.yaml", 2,
     (("common/lib/warns.yaml", WARNS), ("missions/warnuse.yaml", WARNUSE))),
]  # fmt: skip

#: docs/simulator.md's world files: an empty one (comments only, in place of the page's
#: my-flat.yaml), a start whose body reaches over the stairs (tests/cli/
#: test_validate_world.py's), a list of more obstacles than a world may hold
EMPTY_WORLD: Files = (("my-flat.yaml", "# my flat, to be drawn\n"),)
EDGE = world_starting_at(2.9)  # the test's warning, which the page quotes
#: the list is refused by its count before an item is read: empty items cost least to parse
#: (12,000 rectangles took 4 s of CPU)
CROWDED = "name: w\nrooms: [{rect: [0, 0, 50, 50]}]\nobstacles:\n" + "  - {}\n" * 12_000

#: (how the quote begins, the command, its exit code, the files, the stream it prints on)
SIMULATOR_MD: list[tuple[str, str, int, Files, str]] = [
    ("my-flat.yaml:1:1: an empty file", "roomba-bt validate my-flat.yaml", 2, EMPTY_WORLD, "out"),
    ("my-flat.yaml:1:1: (document)", "roomba-bt sensors --world my-flat.yaml --count 1", 2,
     EMPTY_WORLD, "err"),
    ("edge.yaml:7:10: warning:", "roomba-bt validate edge.yaml", 0, (("edge.yaml", EDGE),), "out"),
    ("w.yaml:4:3: obstacles:", "roomba-bt validate w.yaml", 2, (("w.yaml", CROWDED),), "out"),
]  # fmt: skip

#: docs/plugins.md's key parameters ("Key parameters and their types"): the page's own
#: ``dirt_seen`` (its python block, written as the lab's plugin file) given a key declared
#: ``str``, and a ``count_into`` (a key parameter that left ``from_blackboard`` at its
#: default) given ``@pointer``; each in a lab.yaml whose value is at the quoted line:column
PLUGINS_PAGE = Path(__file__).resolve().parents[1] / "docs" / "plugins.md"
KEY_PARAMETERS = PLUGINS_PAGE.read_text(encoding="utf-8").split(
    "\n### Key parameters and their types\n", 1
)[1]
DIRT_SEEN = KEY_PARAMETERS.split("```python\n", 1)[1].split("```", 1)[0]
LAB_DIRT = """\
mission: lab
description: the lab's dirt round
plugins: [dirt.py]
blackboard:
  dirt_level: {type: str, initial: none}
tree:
  sequence:
    - mode: safe
    - wait: 1s
    - wait: 1s
    - wait: 1s
    - wait: 1s
    - wait: 1s
    - fallback:
      - dirt_seen: {level: 2, key: dirt_level}
      - wait: 1s
"""
COUNTING = '''\
from roomba_bt.behaviours import INT, STR, Condition, Param, declare, write_key


@declare("count_into", kind="condition", params=(Param("key", STR, doc="an int key"),),
         writes_keys={"key": INT})
class CountInto(Condition):
    """Writes 1 to the key its parameter names."""

    def check(self, snapshot):
        write_key(str(self.value("key")), 1, self.name)
        return True
'''
LAB_COUNT = """\
mission: lab
plugins: [counting.py]
blackboard:
  count: {type: int, initial: 0}
  pointer: {type: str, initial: count}
tree:
  sequence:
    - count_into: {key: "@pointer"}
"""
PLUGINS_MD: list[tuple[str, Files]] = [
    ("lab.yaml:15:36: dirt_seen.key", (("dirt.py", DIRT_SEEN), ("lab.yaml", LAB_DIRT))),
    ("lab.yaml:8:25: count_into.key", (("counting.py", COUNTING), ("lab.yaml", LAB_COUNT))),
]

#: docs/monitor.md's reload of a watched mission whose plugin file no longer imports: the
#: same compile as ``validate``'s, refused at the line that lists the plugin
BROKEN_PLUGIN: Files = (
    ("main.yaml", "mission: main\nplugins: [broken.py]\ntree:\n  wait: 1s\n"),
    ("broken.py", "def oops(:\n    pass\n"),
)
