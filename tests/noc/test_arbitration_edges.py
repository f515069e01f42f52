"""Two arbitration rules that only show at their edge: the Hermes output release two cycles after the
tail, and the per-output round-robin pointer moving past each winner (docs/noc.md).  Cycle numbers
derived by hand in each docstring from the rules quoted there."""

from __future__ import annotations

from robosoc.chip.noc import Mesh
from robosoc.config.chip import ChipConfig, NocConfig


def test_hermes_output_is_free_two_cycles_after_the_tail() -> None:
    """3x3, 3-flit packets into router (1,1)'s own receive memory: A from (0,1) (WEST), B from (1,0)
    (SOUTH), both injected in 0.

    Each crosses its source router in 5 and requests at (1,1) from 6: S1 6, S2 7 selects W (A) first
    after E, S3 8, S5 9, A crosses 10, its flits 10, 11, 12 (delivered in 12 = s + 5(h + 1) + L - 1): the
    LOCAL output is free from 14.  The controller: S1 11 (B's request is up), S2 12 selects S, S3 13
    finds LOCAL held (a failed attempt), S1 14, S2 15, S3 16, S5 17, B crosses 18: delivered in 20.
    Were the output free one cycle earlier (13), B would cross in 15 and be delivered in 17.  (Through a
    further router the difference would not show: B would queue behind A's tail in the next buffer and
    request 2 cycles after it left, in either case.)"""
    mesh = Mesh(ChipConfig(width=3, height=3))
    mesh.inject((0, 1), (1, 1), [1], at_cycle=0)
    mesh.inject((1, 0), (1, 1), [2], at_cycle=0)
    mesh.run(200)
    assert [(d.flits[2], d.cycle) for d in mesh.deliveries()] == [(1, 12), (2, 20)]


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
