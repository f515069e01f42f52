"""The sampling profiler attributes cycles to functions in proportion to the time they run."""

import textwrap

import pytest

from robosoc.chip.profile import Profile, Sampler
from robosoc.chip.single import SingleCoreSoC
from robosoc.program.elf import load_elf
from robosoc.toolchain import build_elf

PROGRAM = textwrap.dedent(
    """
    static volatile unsigned sink;
    __attribute__((noinline)) void spin(unsigned n) { for (unsigned i = 0; i < n; i++) sink += i; }
    __attribute__((noinline)) void heavy(void) { spin(30000); }
    __attribute__((noinline)) void light(void) { for (unsigned i = 0; i < 10000; i++) sink += i; }
    int main(void) { for (int k = 0; k < 10; k++) { heavy(); light(); } return 0; }
    """
)


def test_profile_shares_follow_the_loop_lengths(tmp_path):
    src = tmp_path / "prof.c"
    src.write_text(PROGRAM)
    elf = build_elf([src], mul=True, opt="-O1")
    soc = SingleCoreSoC()
    soc.load(load_elf(elf))
    profile = Profile(interval=2000)
    result = soc.run(sampler=Sampler(soc, profile, seed=1))
    shares = dict(profile.shares())
    # spin() runs three times the iterations of light()'s loop, with the same loop body
    assert shares["spin"] == pytest.approx(0.75, abs=0.05)
    assert shares["light"] == pytest.approx(0.25, abs=0.05)
    assert profile.total == pytest.approx(result.cycles / 2000, rel=0.1)
    # same seed, same samples
    soc2 = SingleCoreSoC()
    soc2.load(load_elf(elf))
    again = Profile(interval=2000)
    soc2.run(sampler=Sampler(soc2, again, seed=1))
    assert again.samples == profile.samples
