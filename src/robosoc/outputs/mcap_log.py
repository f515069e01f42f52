"""A flight as an MCAP file with ROS 2 messages (``flight.mcap``), readable by Foxglove and rosbag2.

The topics, types and units are :data:`robosoc.outputs.ros2_flight.TOPICS`; messages are CDR
encoded by ``mcap-ros2-support`` with the ``ros2msg`` schema text of each type stored in the file,
log time and header stamp the row's simulated time.  The file is written under a temporary name and
renamed, so an interrupted write leaves no truncated ``flight.mcap``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from mcap_ros2.writer import Writer

from robosoc import output_files
from robosoc.control.flight import ROW_FIELDS
from robosoc.control.flight_log import read_flight_log
from robosoc.outputs.ros2_flight import message_definition, row_messages


def write_flight_mcap(rows: np.ndarray, path: Path) -> int:
    """Write the flight ``rows`` (columns :data:`ROW_FIELDS`) to ``path``; the number of messages.

    Raises:
        ValueError: ``rows`` does not have the columns of a flight.
    """
    if rows.ndim != 2 or rows.shape[1] != len(ROW_FIELDS):
        raise ValueError(f"a flight has {len(ROW_FIELDS)} columns (robosoc.control.flight.ROW_FIELDS)")
    count = 0
    with output_files.atomic_open(path, "wb") as stream:
        writer = Writer(stream)
        schemas = {}
        for row in rows:
            for topic, message, ns in row_messages(row):
                schema = schemas.get(topic.datatype)
                if schema is None:
                    schema = writer.register_msgdef(topic.datatype, message_definition(topic.datatype))
                    schemas[topic.datatype] = schema
                writer.write_message(topic.name, schema, message, log_time=ns, publish_time=ns, sequence=count)
                count += 1
        writer.finish()
    return count


def flight_csv_to_mcap(csv_path: Path, mcap_path: Path) -> int:
    """Convert a flight log (``flight.csv``) to MCAP; the number of messages.

    Raises:
        ValueError: the CSV is not a robosoc flight log.
    """
    return write_flight_mcap(read_flight_log(csv_path), mcap_path)


__all__ = ["flight_csv_to_mcap", "write_flight_mcap"]
