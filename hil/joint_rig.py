"""The emulated antagonistic joint behind the same ports as the single muscle (``sim://joint``).

The physics is :mod:`hil.joint` (two muscles of :mod:`hil.plant` on a pulley); the chips are
the single-muscle rig's (:class:`hil.rig.HilRig`: ADS1x15, MCP4725, GPIO, wire faults) plus a
second MCP4725 for muscle B's valve. The sensors are wired from the rig config's channel table
like the single muscle's (``volts = value / scale + zero``): ``pressure`` (muscle A [bar]),
``pressure_b`` (muscle B [bar]) and ``angle`` [deg], an absolute encoder's angle (its counts,
``JointParams.encoder_counts``) put out as an analog voltage. The valve enable line vents both
muscles.
"""

from __future__ import annotations

from typing import NamedTuple

from edge.hal.clock import Clock
from hil.devices.mcp4725 import MCP4725Emulator
from hil.joint import JointParams, encoder_angle_deg, joint_initial_state, joint_update
from hil.rig import HilRig, Wiring, valve_command_bar

DAC_B_ADDRESS = 0x61
ANGLE_DEG_PER_RAD = 57.29577951308232


class JointOutputs(NamedTuple):
    """Noise-free sensor quantities of the joint."""

    angle_deg: float
    pressure_bar: float  # muscle A
    pressure_b_bar: float  # muscle B


class JointHilRig(HilRig):
    """Two muscles on a pulley, two valves, an angle sensor (see the module docstring).

    Args:
        joint: the joint's geometry and muscles (effects already applied to ``joint.muscle``).
        clock, seed, adc_variant, bus_hz, wiring: as :class:`hil.rig.HilRig`.
    """

    def __init__(
        self,
        joint: JointParams | None = None,
        clock: Clock | None = None,
        seed: int = 0,
        adc_variant: str = "ADS1115",
        bus_hz: float | None = None,
        wiring: Wiring | None = None,
    ) -> None:
        self.joint = joint or JointParams()
        super().__init__(self.joint.muscle, clock, seed, adc_variant, bus_hz, wiring)
        self.dac_b = MCP4725Emulator(self.clock.now)
        self.bus.attach(DAC_B_ADDRESS, self.dac_b)
        self.joint_state = joint_initial_state(self.joint, 0.0, 0.0)
        self.valve_b_stuck_bar: float | None = None

    @property
    def command_b_bar(self) -> float:
        """What muscle B's valve is asked for now [bar] (vented with the shared enable line)."""
        if self.valve_b_stuck_bar is not None:
            return self.valve_b_stuck_bar
        if not self.gpio.level("valve_enable"):
            return 0.0
        return valve_command_bar(self.dac_b.output_volts, self.wiring.valve_b_bar_per_volt)

    def sync(self) -> None:
        """Integrate the joint up to the clock's now."""
        dt = self.joint.dt_s
        now = self.clock.now()
        for hook in self.hooks:
            hook(now)
        u_a, u_b = self.command_bar, self.command_b_bar
        while self._plant_time + dt <= now + 1e-12:
            self.joint_state = joint_update(self._plant_time, self.joint_state, u_a, u_b, self.joint)
            self._plant_time += dt
            self.steps += 1

    def outputs(self) -> JointOutputs:  # type: ignore[override]
        """True (noise-free apart from the encoder's counts) joint outputs now."""
        self.sync()
        x = self.joint_state
        return JointOutputs(encoder_angle_deg(self.joint, x.angle_rad), x.pressure_a_bar, x.pressure_b_bar)

    def stick_valve(self, stuck: bool = True) -> None:
        """Both valves keep their present commands until released."""
        super().stick_valve(stuck)
        self.valve_b_stuck_bar = self.command_b_bar if stuck else None

    def true_angle_deg(self) -> float:
        """The joint angle without the encoder's rounding [deg]."""
        self.sync()
        return self.joint_state.angle_rad * ANGLE_DEG_PER_RAD
