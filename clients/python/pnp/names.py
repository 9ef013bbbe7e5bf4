"""The platform's names (as pnpctl spells them) for the protos' enum values, both ways."""

from __future__ import annotations

from pnp.common.v1 import common_pb2 as common
from pnp.train.v1 import train_service_pb2 as train

ROBOTS = {"fetch": common.ROBOT_FETCH, "panda": common.ROBOT_PANDA}
OBJECTS = {
    "block": common.OBJECT_SHAPE_BLOCK,
    "small_block": common.OBJECT_SHAPE_SMALL_BLOCK,
    "cylinder": common.OBJECT_SHAPE_CYLINDER,
}
WORLDS = {"paper": common.WORLD_PAPER, "gym": common.WORLD_GYM}
# "default": the robot's own (the service decides: docs/SIMULATION.md, "Actuation").
ACTUATIONS = {
    "default": common.ACTUATION_UNSPECIFIED,
    "mocap": common.ACTUATION_MOCAP,
    "arm": common.ACTUATION_ARM,
}
ROLES = {
    "approach": common.ROLE_APPROACH,
    "manipulate": common.ROLE_MANIPULATE,
    "retract": common.ROLE_RETRACT,
    "hlc": common.ROLE_HLC,
    "e2e": common.ROLE_E2E,
}
SUBTASKS = {
    "approach": common.SUBTASK_APPROACH,
    "manipulate": common.SUBTASK_MANIPULATE,
    "retract": common.SUBTASK_RETRACT,
}
ALGORITHMS = {
    "ddpg_her": train.ALGORITHM_DDPG_HER,
    "bc": train.ALGORITHM_BC,
    "bc_offline": train.ALGORITHM_BC_OFFLINE,
    "a3c": train.ALGORITHM_A3C,
}
RUN_STATES = {
    "pending": train.RUN_STATE_PENDING,
    "running": train.RUN_STATE_RUNNING,
    "succeeded": train.RUN_STATE_SUCCEEDED,
    "failed": train.RUN_STATE_FAILED,
    "cancelled": train.RUN_STATE_CANCELLED,
}
TERMINAL_RUN_STATES = ("succeeded", "failed", "cancelled")


def to_enum(table: dict[str, int], name: str, field: str) -> int:
    """The enum value of `name`; ValueError naming `field` and the accepted names otherwise."""
    try:
        return table[name]
    except (KeyError, TypeError):
        raise ValueError(f"{field}: expected one of {', '.join(table)}, got {name!r}") from None


def to_name(table: dict[str, int], value: int) -> str | None:
    """The name of an enum value; None for UNSPECIFIED (not recorded)."""
    for name, v in table.items():
        if v == value:
            return name
    return None
