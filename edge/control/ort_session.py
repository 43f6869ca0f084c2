"""One onnxruntime session for a per-tick net: single-threaded, sequential, CPU only.

A 1 kHz tick evaluates one small step at a time, so thread pools would only add wake-up latency;
every net the edge runs (the correction, the LSTM-NARMAX, Hammerstein and state-space step graphs) is opened
here, and a file onnxruntime cannot load is one :class:`BundleError` line.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from edge.errors import BundleError


def tick_session(path: Path, what: str = "the net") -> Any:
    """An ``onnxruntime.InferenceSession`` of ``path`` for per-tick use; ``what`` names the model
    in the error line."""
    import onnxruntime as ort  # on the SBC only when a bundle holds a net

    options = ort.SessionOptions()
    options.intra_op_num_threads = 1
    options.inter_op_num_threads = 1
    options.execution_mode = ort.ExecutionMode.ORT_SEQUENTIAL
    try:
        return ort.InferenceSession(str(path), options, providers=["CPUExecutionProvider"])
    except Exception as exc:  # onnxruntime raises its own exception types for a corrupt model
        raise BundleError(f"{path}: onnxruntime cannot load {what} ({exc}); re-export the bundle") from exc
