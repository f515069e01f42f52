"""A bag read back with ``rosbags`` (a reader no part of robosoc wrote): every message of every
topic decoded with the types the file itself carries, and the file converted with
``rosbags-convert`` (run as the installed command's module, ``python -m rosbags.convert``)."""

from __future__ import annotations

import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

from rosbags.highlevel import AnyReader


@dataclass(frozen=True)
class Message:
    msgtype: str
    timestamp: int  # the log time, ns since the Unix epoch
    message: object  # the decoded message
    raw: bytes  # as stored (CDR for ROS 2, ROS 1 serialization for a ROS 1 bag)


@dataclass(frozen=True)
class Bag:
    connections: list  # rosbags' Connection records (topic, msgtype, digest, ext with the QoS)
    typestore: object  # the types read from the file
    is2: bool  # a ROS 2 bag (MCAP or rosbag2), not a ROS 1 bag


def read_bag(path: Path) -> tuple[dict[str, list[Message]], Bag]:
    """Every message of ``path`` decoded, by topic, in log-time order; and what the reader saw."""
    out: dict[str, list[Message]] = {}
    with AnyReader([path]) as reader:
        for connection, timestamp, raw in reader.messages():
            decoded = reader.deserialize(raw, connection.msgtype)
            out.setdefault(connection.topic, []).append(Message(connection.msgtype, timestamp, decoded, bytes(raw)))
        return out, Bag(list(reader.connections), reader.typestore, reader.is2)


def convert(src: Path, dst: Path) -> subprocess.CompletedProcess[str]:
    """``rosbags-convert --src SRC --dst DST`` (DST ``*.bag``: a ROS 1 bag)."""
    args = [sys.executable, "-m", "rosbags.convert", "--src", str(src), "--dst", str(dst)]
    return subprocess.run(args, capture_output=True, text=True, timeout=120, check=False)


def field(message: object, path: str) -> object:
    """The field at a dotted path (``transforms.0.transform.translation.x``)."""
    node = message
    for key in path.split("."):
        node = node[int(key)] if key.isdigit() else getattr(node, key)
    return node
