"""Coupling the chip with the world: replaying recorded sensor streams into the firmware.

:mod:`robosoc.cosim.replay` drives the control firmware on the MPSoC with a recorded flight's
sensor samples and returns its commands and one record per job of each task.
"""
