"""pmactl edge runtime: what runs on the rig's single-board computer.

Imports only numpy (plus onnxruntime, onnx, smbus2, pyserial, gpiod, foxglove-sdk in the runtime parts).
Never imports ``host``, ``hil`` or ``models_export``.
"""

__version__ = "0.1.0"
