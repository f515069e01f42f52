"""robosoc: robot control firmware on a cycle-accurate simulated RISC-V MPSoC, closed-loop with physics."""

__version__ = "0.1.0"
