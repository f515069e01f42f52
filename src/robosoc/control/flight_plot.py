"""A PNG summary of a flight: height, roll, pitch, yaw (truth, estimate, setpoint) and PWM."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from robosoc.control.flight import column
from robosoc.output_files import save_figure


def plot_flight(rows: np.ndarray, path: Path, title: str = "") -> None:
    """Write a five-panel plot of the flight array ``rows`` to ``path`` (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = column(rows, "t")
    fig, axes = plt.subplots(5, 1, figsize=(10, 12), sharex=True)
    ax = axes[0]
    ax.plot(t, column(rows, "z"), label="truth")
    ax.plot(t, column(rows, "est_height"), label="estimate", alpha=0.8)
    ax.plot(t, column(rows, "sp_height"), "--", label="setpoint")
    ax.set_ylabel("height [m]")
    ax.legend(loc="lower right")
    for ax, axis in zip(axes[1:4], ("roll", "pitch", "yaw"), strict=True):
        ax.plot(t, np.degrees(column(rows, axis)), label="truth")
        ax.plot(t, np.degrees(column(rows, f"est_{axis}")), label="estimate", alpha=0.8)
        ax.plot(t, np.degrees(column(rows, f"sp_{axis}")), "--", label="setpoint")
        ax.set_ylabel(f"{axis} [deg]")
        ax.legend(loc="lower right")
    ax = axes[4]
    for i in range(4):
        ax.plot(t, column(rows, f"pwm{i}"), label=f"motor {i}", linewidth=0.8)
    ax.set_ylabel("PWM")
    ax.set_xlabel("time [s]")
    ax.legend(loc="lower right", ncol=4)
    for ax in axes:
        ax.grid(alpha=0.3)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    save_figure(fig, path, dpi=100)
    plt.close(fig)
