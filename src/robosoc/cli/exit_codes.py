"""Exit codes of every ``robosoc`` command (docs/cli.md), and the text ``--help`` shows for them."""

#: The command did what it was asked.
OK = 0
#: A bug in robosoc: the traceback is printed with a request to report it.
INTERNAL_ERROR = 1
#: A usage or input error: a bad option value, a missing or malformed input file, an output path
#: that cannot be written, a program that does not compile.  Nothing long has run.
USAGE = 2
#: ``robosoc run``: the simulator stopped the program (a fault, the cycle budget, a chip that
#: cannot make progress); ``robosoc fly``: the firmware failed on the chip.  With
#: ``--exit-code status`` (the default) no program exit gives it.
SIMULATOR_STOP = 3
#: ``robosoc run --exit-code status``: the program exited with a non-zero exit code (printed on
#: stderr and kept in the stats file).
PROGRAM_FAILED = 4
#: ``robosoc serve physics|chip``, ``robosoc fly --decoupled``: the other side went silent for
#: ``--peer-timeout`` (or never answered within ``--connect-timeout``) or ended early; what was
#: done so far is written.
PEER_LOST = 5
#: ``robosoc sweep``: every run of the sweep failed (each with its reason in the table).
ALL_FAILED = 3
#: Interrupted (Ctrl-C); whatever was written so far is kept.
INTERRUPTED = 130
#: The reader of the output went away (``robosoc ... | head``), as a shell reports SIGPIPE.
BROKEN_PIPE = 141

#: Exit-code choices of ``robosoc run --exit-code``.
EXIT_CODE_STATUS = "status"
EXIT_CODE_PROGRAM = "program"

EPILOG = "Exit codes: 0 success, 1 internal error (a bug: please report it), 2 usage or input error, 130 interrupted."

FLY_EPILOG = (
    "Exit codes: 0 success, 1 internal error (a bug: please report it), 2 usage or input error, "
    "3 the firmware failed on the chip, 130 interrupted; after 3 and 130 the run folder keeps the flight so far "
    "(flight.csv, and summary.json with complete false)."
)

SERVE_EPILOG = (
    "Exit codes: 0 success, 1 internal error (a bug: please report it), 2 usage or input error "
    "(also: the address is in use, the firmware faulted), 5 the other side went silent for --peer-timeout, "
    "never answered within --connect-timeout, or ended early, 130 interrupted."
)

SWEEP_EPILOG = (
    "Exit codes: 0 success (some points may have failed: see the table), 1 internal error (a bug: please "
    "report it), 2 usage or input error (also: the output folder is in use by another sweep, a record in it "
    "is malformed, or it cannot be written), 3 every run failed, 130 interrupted (the finished points are kept)."
)

RUN_EPILOG = (
    "Exit codes: 0 the program exited with 0, 1 internal error (a bug: please report it), "
    "2 usage or input error, 3 the simulator stopped the program (fault, cycle budget, no progress), "
    "4 the program exited with a non-zero code (its code is on stderr and in --stats), 130 interrupted. "
    "With --exit-code program, the program's own exit code (mod 256) replaces 0 and 4; "
    "3 and 130 keep their meaning but a program may return them too."
)

__all__ = [
    "ALL_FAILED",
    "BROKEN_PIPE",
    "EPILOG",
    "EXIT_CODE_PROGRAM",
    "EXIT_CODE_STATUS",
    "FLY_EPILOG",
    "INTERNAL_ERROR",
    "INTERRUPTED",
    "OK",
    "PEER_LOST",
    "PROGRAM_FAILED",
    "RUN_EPILOG",
    "SERVE_EPILOG",
    "SIMULATOR_STOP",
    "SWEEP_EPILOG",
    "USAGE",
]
