"""LinuxCNC's step types: 0 step/dir, 1 up/down, 2–14 state tables, 15 user-defined.

The tables are LinuxCNC ``stepgen.c``'s (the ``step_type`` list of LinuxCNC's stepgen manual page).
Phase A is bit 0 of each state value; forward motion walks the states upward, reverse downward,
wrapping. The validator's decoder and the stepgen model both use this one table.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

from wavecheck.errors import ConfigError
from wavecheck.record import record

__all__ = ["PHASE_NAMES", "STATE_TABLES", "StepKind", "StepType", "kind_of", "step_type"]

StepKind = Literal["step-dir", "up-down", "phases"]
"""What a step type puts on the wire: STEP + DIR, UP + DOWN pulses, or phase states."""

PHASE_NAMES: tuple[str, ...] = ("phase-A", "phase-B", "phase-C", "phase-D", "phase-E")

#: type → (name, state values); cycle length = len(values).
STATE_TABLES: dict[int, tuple[str, tuple[int, ...]]] = {
    2: ("quadrature", (1, 3, 2, 0)),
    3: ("three wire", (1, 2, 4)),
    4: ("three wire half step", (1, 3, 2, 6, 4, 5)),
    5: ("unipolar full step, one winding on", (1, 2, 4, 8)),
    6: ("unipolar full step, two windings on", (3, 6, 12, 9)),
    7: ("bipolar full step, one winding on", (1, 7, 14, 8)),
    8: ("bipolar full step, two windings on", (5, 6, 10, 9)),
    9: ("unipolar half step", (1, 3, 2, 6, 4, 12, 8, 9)),
    10: ("bipolar half step", (1, 5, 7, 6, 14, 10, 8, 9)),
    11: ("five wire unipolar", (1, 2, 4, 8, 16)),
    12: ("five wire wave", (3, 6, 12, 24, 17)),
    13: ("five wire unipolar half step", (1, 3, 2, 6, 4, 12, 8, 24, 16, 17)),
    14: ("five wire wave half step", (3, 7, 6, 14, 12, 28, 24, 25, 17, 19)),
}
_PHASES = {2: 2, 3: 3, 4: 3, 5: 4, 6: 4, 7: 4, 8: 4, 9: 4, 10: 4, 11: 5, 12: 5, 13: 5, 14: 5}
MAX_USER_CYCLE = 18  # LinuxCNC 2.9/master (10 in <= 2.8 and machinekit)


@record(frozen=True)
class StepType:
    """One step type: its outputs and, for types >= 2, its state table."""

    number: int
    name: str
    outputs: tuple[str, ...]
    states: tuple[int, ...] = ()

    @property
    def kind(self) -> StepKind:
        """``step-dir`` (type 0), ``up-down`` (type 1) or ``phases`` (2–15)."""
        return kind_of(self.number)

    @property
    def pulse_roles(self) -> tuple[str, ...]:
        """The roles whose edges are steps: ``step``, ``up``/``down``, or the phase outputs."""
        return ("step",) if self.kind == "step-dir" else self.outputs

    @property
    def cycle(self) -> int:
        """Number of states in the cycle (0 for types 0 and 1)."""
        return len(self.states)


def kind_of(number: int) -> StepKind:
    """The kind of step type ``number`` (no table needed, so type 15 without one works)."""
    return "step-dir" if number == 0 else "up-down" if number == 1 else "phases"


def step_type(number: int, user_table: Sequence[int] | None = None) -> StepType:
    """The step type ``number``; type 15 needs ``user_table`` (LinuxCNC's ``user_step_type=``).

    Raises:
        ConfigError: a type outside 0..15, or a bad user table.
    """
    if number == 0:
        return StepType(0, "step/dir", ("step", "dir"))
    if number == 1:
        return StepType(1, "up/down", ("up", "down"))
    if number in STATE_TABLES:
        name, states = STATE_TABLES[number]
        return StepType(number, name, PHASE_NAMES[: _PHASES[number]], states)
    if number == 15:
        if not user_table:
            raise ConfigError("step type 15 needs a user table (e.g. --user-step-type 1,3,2,0)")
        table = tuple(int(v) for v in user_table)
        if len(table) > MAX_USER_CYCLE:
            raise ConfigError(
                f"user step table has {len(table)} states; LinuxCNC accepts at most {MAX_USER_CYCLE}"
            )
        if any(v < 0 or v >= 32 for v in table):
            raise ConfigError(
                f"user step table {list(table)} uses a bit above phase-E (values 0..31)"
            )
        phases = max(max(table).bit_length(), 1)
        return StepType(15, "user-defined", PHASE_NAMES[:phases], table)
    raise ConfigError(f"step type {number} does not exist (LinuxCNC accepts 0..15)")
