"""The tick as data: one preallocated row that every stage of a tick fills.

The row is a ``ctypes.Structure`` (stages set fields as attributes, ~50 ns each) and the same
memory is a numpy structured row (:attr:`FrameLayout.dtype`, :meth:`FrameLayout.as_array`),
which telemetry copies whole. Fields, in order:

* ``t`` [s], ``lateness_us``, ``reference_mm``, ``u_ff_bar`` / ``u_nn_bar`` / ``u_fb_bar``
  (feedforward, neural correction, feedback), ``u_bar`` (the valve command, 0 when vented); on
  a joint ``reference_deg``, ``u_ff_deg`` / ``u_fb_deg`` (commanded angles) and ``u_bar`` (valve
  A; valve B is its ``valve_b_bar`` channel field);
* on a single muscle, the forward twin (:mod:`edge.control.twin`): ``twin_mm`` (predicted
  contraction) and ``twin_residual_mm`` (measured - predicted), and the online adaptation
  (:mod:`edge.control.adapt`): ``adapt_offset_mm``, ``adapt_gain``; NaN when not running;
* one field per channel (``contraction_mm``, ``pressure_bar``, ``estop``, ``valve_enable``,
  ``load_N``...), NaN when its device could not be read this tick;
* ``state`` and ``fault`` codes (:class:`edge.runtime.safety.State` order, ``Fault`` values);
* per device ``rd_<device>`` and ``wr_<device>``: the errno of this tick's read and of the
  latest write (0 = ok). The supervisor checks all of them with one rule.
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass

import numpy as np

from edge.runtime.rigspec import RigSpec

CONTROL_FIELDS = ("t", "lateness_us", "reference_mm", "u_ff_bar", "u_nn_bar", "u_fb_bar", "u_bar")
TWIN_FIELDS = ("twin_mm", "twin_residual_mm", "adapt_offset_mm", "adapt_gain")  # NaN unless running
# a joint's feedforward and feedback are commanded angles (edge.control.joint); u_bar is valve A
JOINT_CONTROL_FIELDS = ("t", "lateness_us", "reference_deg", "u_ff_deg", "u_fb_deg", "u_bar")
CODE_FIELDS = ("state", "fault")


@dataclass(frozen=True)
class FrameLayout:
    """The frame type of one rig: its ctypes class, numpy dtype and which fields mean what."""

    cls: type[ctypes.Structure]
    dtype: np.dtype
    channel_fields: tuple[str, ...]
    status_fields: tuple[tuple[str, str, str], ...]  # (device, read field, write field)
    status_offset: int  # bytes: where the rd_/wr_ fields start (they are contiguous)
    nan_fields: tuple[str, ...] = ()  # NaN in a new frame besides the channels (the twin's)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(self.dtype.names or ())

    def new(self) -> ctypes.Structure:
        """A zeroed frame with every channel NaN (nothing read yet); it satisfies
        :class:`edge.control.law.TickFrame` and the rig's law's frame protocol (fields by name)."""
        frame = self.cls()
        for name in (*self.channel_fields, *self.nan_fields):
            setattr(frame, name, float("nan"))
        return frame

    def status_view(self, frame: ctypes.Structure) -> ctypes.Array[ctypes.c_char]:
        """A ctypes byte array over every ``rd_*`` / ``wr_*`` field of ``frame`` (all zero: all ok)."""
        return (ctypes.c_char * (self.dtype.itemsize - self.status_offset)).from_buffer(frame, self.status_offset)

    def bytes_view(self, frame: ctypes.Structure) -> memoryview:
        """The frame's memory as bytes (telemetry copies it whole)."""
        return memoryview(frame).cast("B")

    def as_array(self, frame: ctypes.Structure) -> np.ndarray:
        """The frame's memory as a one-row numpy structured array (no copy)."""
        return np.frombuffer(self.bytes_view(frame), dtype=self.dtype, count=1)


def frame_layout(rig: RigSpec) -> FrameLayout:
    """The frame of ``rig`` (see the module docstring)."""
    floats = list(JOINT_CONTROL_FIELDS if rig.is_joint else CONTROL_FIELDS + TWIN_FIELDS)  # a copy: appended below
    channel_fields = []
    for always in (rig.output_field, "pressure_bar", "estop", "valve_enable"):  # the controller's
        if always not in {c.field for c in rig.channels}:
            floats.append(always)
            channel_fields.append(always)
    for channel in rig.channels:
        if channel.field not in floats:
            floats.append(channel.field)
            channel_fields.append(channel.field)
    ints = list(CODE_FIELDS)
    status = []
    for device in rig.devices:
        read, write = f"rd_{device.name}", f"wr_{device.name}"
        ints += [read, write]
        status.append((device.name, read, write))
    fields = [(n, ctypes.c_double) for n in floats] + [(n, ctypes.c_int32) for n in ints]
    cls = type("Frame", (ctypes.Structure,), {"_pack_": 1, "_fields_": fields})
    dtype = np.dtype([(n, "<f8") for n in floats] + [(n, "<i4") for n in ints])
    if dtype.itemsize != ctypes.sizeof(cls):
        raise RuntimeError("frame layout: ctypes and numpy disagree on the row size")
    status_offset = 8 * len(floats) + 4 * len(CODE_FIELDS)
    nan_fields = () if rig.is_joint else TWIN_FIELDS
    return FrameLayout(cls, dtype, tuple(channel_fields), tuple(status), status_offset, nan_fields)
