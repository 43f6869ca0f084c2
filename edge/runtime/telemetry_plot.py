"""``pmactl edge telemetry --plot``: a three-panel figure (needs matplotlib, the host extra)."""

from __future__ import annotations

from pathlib import Path

from edge.errors import DataError
from edge.runtime.telemetry_read import Telemetry


def plot(record: Telemetry, path: Path) -> None:
    """Contraction (a joint's angle) vs reference, the command and its parts (a joint's two valve
    commands), lateness; written to ``path``."""
    try:
        import matplotlib
    except ImportError as exc:
        raise DataError(
            "--plot needs matplotlib, which the SBC install leaves out (pip install 'pmactl[host]'); "
            "--csv and --mcap work without it"
        ) from exc

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = record.column("t")
    fig, axes = plt.subplots(3, 1, figsize=(10, 8), sharex=True)
    joint = "angle_deg" in record.columns  # an antagonistic joint (edge.control.joint)
    output, unit = ("angle", "deg") if joint else ("contraction", "mm")
    axes[0].plot(t, record.column(f"reference_{unit}"), label="reference")
    axes[0].plot(t, record.column(f"{output}_{unit}"), label="measured")
    axes[0].set_ylabel(f"{output} [{unit}]")
    axes[0].legend(loc="upper right")
    for name in ("u_bar", "valve_b_bar") if joint else ("u_ff_bar", "u_nn_bar", "u_fb_bar", "u_bar"):
        axes[1].plot(t, record.column(name), label=name.removesuffix("_bar"))
    axes[1].set_ylabel("valve commands [bar]" if joint else "pressure command [bar]")
    axes[1].legend(loc="upper right", ncol=4)
    axes[2].plot(t, record.column("lateness_us"), lw=0.5)
    axes[2].set_ylabel("lateness [us]")
    axes[2].set_xlabel("t [s]")
    fig.suptitle(f"{record.header.get('reference')} ({record.header.get('rate_hz')} Hz)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
