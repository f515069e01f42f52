"""Lets the test modules import their helpers (program_list, line_checks) by name."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
