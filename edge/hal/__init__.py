"""Hardware ports (I2C, GPIO, clock) and their Linux backends.

Drivers in ``edge.devices`` are written against the ports only, so the same driver runs on
``/dev/i2c-1`` through smbus2 and on the HIL emulator's chips in CI.
"""
