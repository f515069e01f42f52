"""The firmware's host side: the packet formats (written once, C header generated), the control
parameters the C builds take from the configs, kernel images and their job log, and the flight
application's build and mapping.  The C itself lives in :mod:`robosoc.firmware`."""
