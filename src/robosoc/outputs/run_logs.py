"""The files a fly run folder gets beside its log: ``flight.mcap``, ``chip-trace.json``, ``report.html``.

:func:`write_run_logs` is the one call ``robosoc fly`` makes at the end of a flight, after its
``flight.csv``, ``jobs.csv`` and ``summary.json`` are written (the report reads them back).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from robosoc.cosim.firmware_run import FirmwareRun, ReplayResult
from robosoc.outputs.chip_trace import run_trace, write_chip_trace
from robosoc.outputs.mcap_log import write_flight_mcap
from robosoc.outputs.report import write_report
from robosoc.outputs.run_folder import CHIP_TRACE_JSON, FLIGHT_MCAP


def write_run_logs(
    folder: Path,
    rows: np.ndarray,
    run: FirmwareRun | None = None,
    result: ReplayResult | None = None,
    metadata: dict[str, object] | None = None,
    telemetry: Mapping[str, np.ndarray] | None = None,
) -> dict[str, Path]:
    """Write the flight's MCAP, the chip's trace (for a chip flight whose chip recorded its
    timeline) and the report into ``folder``; the paths written, by kind.  ``telemetry``: the
    firmware's values under names of its own, one per row (a topic each in the MCAP file).

    Raises:
        robosoc.outputs.run_folder.RunFolderError: a run file in ``folder`` is malformed.
    """
    written = {"mcap": folder / FLIGHT_MCAP}
    write_flight_mcap(rows, written["mcap"], telemetry=telemetry)
    if run is not None and result is not None and run.chip.recording:
        written["trace"] = folder / CHIP_TRACE_JSON
        write_chip_trace(run_trace(run, result, metadata), written["trace"])
    written["report"] = write_report(folder)
    return written


__all__ = ["write_run_logs"]
