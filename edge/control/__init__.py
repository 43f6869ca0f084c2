"""The pure control law: PID, feedforward and limits; no I/O, no clock reads."""
