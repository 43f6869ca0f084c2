"""Chip drivers and the serial DAQ protocol, written against the ``edge.hal`` ports."""
