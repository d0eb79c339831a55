"""Same world, seed and input bytes: the same output bytes, byte for byte."""

from __future__ import annotations

from roomba_bt.oi import commands as C
from roomba_bt.sim import Simulator, load_world


def session(seed: int) -> bytes:
    sim = Simulator(load_world("apartment"), seed=seed, random_start=True)
    out = bytearray()
    script = {
        0: C.start().data + C.stream([100]).data + C.clean().data,
        2000: C.safe().data + C.drive(250, 300).data,
        2600: C.full().data + C.drive(-200, -1).data + C.query_list([35, 7, 19, 20]).data,
        3000: C.start().data + C.max_clean().data,
    }
    for tick in range(4000):
        if tick in script:
            sim.receive(script[tick])
            out += sim.read()
        sim.step()
        out += sim.read()
    return bytes(out)


def test_same_seed_same_bytes() -> None:
    assert session(7) == session(7)


def test_another_seed_starts_elsewhere_and_sends_other_bytes() -> None:
    world = load_world("apartment")
    assert world.sample_start(7) != world.sample_start(8)
    assert session(7) != session(8)
