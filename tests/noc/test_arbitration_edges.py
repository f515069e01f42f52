"""Two arbitration rules that only show at their edge: the Hermes output release two cycles after the
tail, and the per-output round-robin pointer moving past each winner (docs/noc.md).  Cycle numbers
derived by hand in each docstring from the rules quoted there."""

from __future__ import annotations

from robosoc.chip.noc import Mesh
from robosoc.config.chip import ChipConfig, NocConfig


def test_hermes_output_is_free_two_cycles_after_the_tail() -> None:
    """3x1 line, 3-flit packets. A: (0,0) -> (2,0) injected in 0; B: (1,0) -> (2,0) injected in 5.

    A at (0,0): request 1, S2 2, S3 3, S5 4, crosses 5; at (1,0) requests 6.  B is at the head of (1,0)'s
    LOCAL buffer in 6 and requests then too; S1 6, S2 7 selects W (A) first after E; A crosses 10, its
    flits 10, 11, 12: EAST is free from 14.  The controller: S1 11 (B's request is up), S2 12, S3 13 finds
    EAST held (a failed attempt), S1 14, S2 15, S3 16, S5 17, B crosses 18.  At (2,0): A arrived 10,
    crossed into the receive memory 15, last flit 17 (s + 5(h + 1) + L - 1); LOCAL free from 19.  B arrives
    18, requests 19, S2 20, S3 21, S5 22, crosses 23: last flit 25.  Were EAST free one cycle earlier (13),
    B would cross (1,0) in 15 and finish in 22."""
    mesh = Mesh(ChipConfig(width=3, height=1))
    mesh.inject((0, 0), (2, 0), [1], at_cycle=0)
    mesh.inject((1, 0), (2, 0), [2], at_cycle=5)
    mesh.run(200)
    assert [(d.flits[2], d.cycle) for d in mesh.deliveries()] == [(1, 17), (2, 25)]


def test_per_output_pointer_moves_past_each_winner() -> None:
    """Router (1,1) of a 3x3, every packet to (1,2) through its NORTH output (per-output arbiters, R = 4):
    EAST ((2,1), two packets back to back), WEST ((0,1)), SOUTH ((1,0)) and LOCAL ((1,1), from 5) all
    request NORTH in the same cycle; the pointer starts at EAST: E wins, then W (just past E).  E's second
    header reaches the head when the first tail leaves and requests 4 cycles later, while W holds the
    output; when W's tail is gone, E, S and L all request: the pointer is just past W, so S wins, then L,
    and E's second packet comes last.  A pointer that did not move would serve E again before S."""
    mesh = Mesh(ChipConfig(width=3, height=3, noc=NocConfig(arbiter="per-output")), tag_packets=True)
    for src in [(2, 1), (2, 1), (0, 1), (1, 0)]:
        mesh.inject(src, (1, 2), [0, 0], at_cycle=0)
    mesh.inject((1, 1), (1, 2), [0, 0], at_cycle=5)
    mesh.run(500)
    assert [d.src for d in mesh.deliveries()] == [(2, 1), (0, 1), (1, 0), (1, 1), (2, 1)]
