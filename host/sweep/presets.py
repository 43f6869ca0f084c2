"""Job kinds: what a cell of each kind runs by default, what it needs, which columns are timing.

A preset is data, not code: the ``pmactl`` command line each cell runs (``{name}``
placeholders), default values, named choices (``controller = "pid"`` -> the flags that select
PID alone), the resources a cell reserves (CPU, memory, custom resources such as ``pma_rig``),
and the metric columns that measure time and so differ between runs. A matrix overrides any of
it; ``[[steps]]`` in a matrix replaces the preset's steps as a whole.

Every cell goes through the stable command line (``pmactl ... --json``), never through Python
internals, so fit, diagnose and the edge runtime can change inside without breaking sweeps.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from host.sweep.template import Value


@dataclass(frozen=True)
class Step:
    """One command of a cell.

    ``args`` are ``pmactl`` arguments, or with ``program = true`` a whole command line (the
    first element the executable; ``{python}`` is this Python). ``json`` says where the step's
    result is: ``"stdout"``, ``"file:NAME"`` (relative to the cell's directory) or ``"none"``.
    """

    name: str
    args: tuple[str, ...]
    json: str = "stdout"
    program: bool = False


@dataclass(frozen=True)
class Resources:
    """What one cell reserves: CPUs (also its thread count), memory [MB], custom resources."""

    num_cpus: float = 1.0
    memory_mb: int = 512
    custom: dict[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class JobKind:
    name: str
    description: str
    steps: tuple[Step, ...]
    defaults: dict[str, Value]
    choices: dict[str, dict[str, Value]]
    resources: Resources
    files: dict[str, dict[str, object]] = field(default_factory=dict)
    timing_columns: tuple[str, ...] = ()


# Columns that measure time or scheduling: excluded when comparing two runs of one matrix.
COMMON_TIMING = ("elapsed_s", "cpu_s", "host", "attempts", "*.fit_seconds", "*seconds*")

CONTROLLERS: dict[str, Value] = {
    "pid": ["--no-feedforward", "--no-correction"],
    "pid+ff": ["--no-correction"],
    "pid+ff+nn": [],  # the bundle's ONNX correction on; a bundle without one runs PID+FF
}

SIM_IO = "sim://rig?adc=ADS1015&clock=lockstep&effect={effect}&seed={seed}"

# fmt: off
KINDS: dict[str, JobKind] = {
    kind.name: kind
    for kind in (
        JobKind(
            name="hil-run",
            description="the edge loop closed on the emulated rig (pmactl edge run) with a hidden effect per cell",
            steps=(
                Step(
                    "run",
                    (
                        "edge", "run", "--config", "{config}", "--bundle", "{bundle}", "--duration", "{duration}",
                        "--settle", "{settle}", "--reference", "{reference}", "{controller}", "{extra}", "--json",
                    ),
                ),
            ),
            defaults={
                "duration": 25,
                "settle": 5,
                "reference": "sine:amplitude=30,frequency=0.2,offset=40",
                "controller": "pid+ff",
                "effect": "none",
                "extra": [],
            },
            choices={"controller": CONTROLLERS},
            resources=Resources(num_cpus=1, memory_mb=512),
            files={"config": {"template": "{hil_config}", "name": "rig.toml", "set": {"buses.i2c.url": SIM_IO}}},
            timing_columns=("*lateness*", "*.overruns*", "*.realtime"),
        ),
        JobKind(
            name="hil-record",
            description="a recording of a test protocol on the emulated rig (pmactl hil record)",
            steps=(
                Step(
                    "record",
                    (
                        "hil", "record", "--scenario", "{scenario}", "--seed", "{seed}", "--duration", "{duration}",
                        "--effect", "{effect}", "--rate", "{rate}", "--out", "recording.csv", "{extra}",
                    ),
                    json="none",
                ),
            ),
            defaults={"scenario": "mixed", "duration": 60, "effect": "none", "rate": 100, "extra": []},
            choices={},
            resources=Resources(num_cpus=1, memory_mb=256),
        ),
        JobKind(
            name="fit",
            description="identification of a hysteresis model, scored on held-out data (pmactl fit --json)",
            steps=(
                Step("fit", ("fit", "--model", "{model}", "--train", "{train}", "--test", "{test}", "{extra}",
                             "--json")),
            ),
            defaults={"model": "pi", "train": "{example_train}", "test": "{example_test}", "extra": []},
            choices={},
            resources=Resources(num_cpus=1, memory_mb=1024),
        ),
        JobKind(
            name="diagnose",
            description="what the simulation gets wrong on one recording (pmactl diagnose --json)",
            steps=(
                Step(
                    "diagnose",
                    ("diagnose", "{data}", "--folds", "{folds}", "--json", "diagnose.json", "{extra}"),
                    json="file:diagnose.json",
                ),
            ),
            defaults={"folds": 4, "extra": []},
            choices={},
            resources=Resources(num_cpus=1, memory_mb=1024),
        ),
        JobKind(
            name="train",
            description="training of a neural correction; give the command as [[steps]] (pmactl train owns its flags)",
            steps=(),
            defaults={"extra": []},
            choices={},
            resources=Resources(num_cpus=2, memory_mb=2048),
        ),
    )
}
# fmt: on
