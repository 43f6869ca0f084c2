"""pmactl edge runtime: what runs on the rig's single-board computer.

Imports only numpy (plus onnxruntime, smbus2, pyserial and gpiod in the runtime parts).
Never imports ``host``, ``hil`` or ``models_export``.
"""

__version__ = "0.1.0"
