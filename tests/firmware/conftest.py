"""Lets the test modules import their helpers (flight_data, c_runs) by name."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
