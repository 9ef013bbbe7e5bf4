"""The services' records (runs, metric points, checkpoints, served roles) as plain dicts
with the platform's names ("approach", "succeeded", "gym"), times as UNIX seconds."""

from __future__ import annotations

from pnp import names


def _seconds(timestamp) -> float | None:
    if not timestamp.seconds and not timestamp.nanos:
        return None  # not set
    return timestamp.seconds + timestamp.nanos * 1e-9


def _outcome(state: str, reached: bool) -> str:
    """As pnpctl and the dashboard show a run: a finished one "reached" its target or is
    "not-reached" (stopped at its step cap); otherwise its state."""
    if state != "succeeded":
        return state
    return "reached" if reached else "not-reached"


def run_record(run) -> dict:
    return {
        "run_id": run.run_id,
        "role": names.to_name(names.ROLES, run.role),
        "algorithm": names.to_name(names.ALGORITHMS, run.algorithm),
        "robot": names.to_name(names.ROBOTS, run.robot),
        "object": names.to_name(names.OBJECTS, run.object),
        "world": names.to_name(names.WORLDS, run.world),
        "actuation": names.to_name(names.ACTUATIONS, run.actuation),
        "seed": run.seed,
        "state": names.to_name(names.RUN_STATES, run.state),
        "outcome": _outcome(names.to_name(names.RUN_STATES, run.state), run.reached),
        "env_steps": run.env_steps,
        "max_steps": run.max_steps,
        "last_success": run.last_success,
        "last_score": run.last_score if run.HasField("last_score") else None,
        "target_success": run.target_success,
        "reached": run.reached,
        "steps_to_target": run.steps_to_target if run.reached else None,
        "latest_checkpoint_id": run.latest_checkpoint_id or None,
        "parent_checkpoint_id": run.parent_checkpoint_id or None,
        "error": run.error or None,
        "code_commit": run.code_commit,
        "config_json": run.config_json,
        "create_time": _seconds(run.create_time),
        "update_time": _seconds(run.update_time),
        "finish_time": _seconds(run.finish_time),
        "wall_breakdown": {
            phase: getattr(run.wall_breakdown, phase)
            for phase in ("rollout_s", "update_s", "eval_s", "report_s", "other_s", "total_s")
        },
    }


def metric_record(point) -> dict:
    return {
        "env_steps": point.env_steps,
        "episodes": point.episodes,
        "wall_s": point.wall_s,
        "task_success": point.task_success,
        "subtask_success": point.subtask_success,
        "sampled_success": point.sampled_success,
        "critic_loss": point.critic_loss,
        "actor_loss": point.actor_loss,
        "updates": point.updates,
        "stop_score": point.stop_score if point.HasField("stop_score") else None,
    }


def checkpoint_record(checkpoint) -> dict:
    return {
        "checkpoint_id": checkpoint.checkpoint_id,
        "run_id": checkpoint.run_id,
        "role": names.to_name(names.ROLES, checkpoint.role),
        "env_steps": checkpoint.env_steps,
        "evaluated": checkpoint.evaluated,
        "eval_success": checkpoint.eval_success if checkpoint.evaluated else None,
        "checksum": checkpoint.checksum,
        "size_bytes": checkpoint.size_bytes,
        "create_time": _seconds(checkpoint.create_time),
    }


def served_role_record(role) -> dict:
    return {
        "role": names.to_name(names.ROLES, role.role),
        "checkpoint_id": role.checkpoint_id,
        "robot": names.to_name(names.ROBOTS, role.robot),
        "object": names.to_name(names.OBJECTS, role.object),
        "world": names.to_name(names.WORLDS, role.world),
        "actuation": names.to_name(names.ACTUATIONS, role.actuation),
        "promote_time": _seconds(role.promote_time),
        "promoted_by": role.promoted_by or None,
    }


def promoted_record(p) -> dict:
    return {
        "role": names.to_name(names.ROLES, p.role),
        "checkpoint_id": p.checkpoint_id,
        "run_id": p.run_id,
        "env_steps": p.env_steps,
        "latest_of_run": p.latest_of_run,
    }


def as_table(rows: list[dict]):
    """A pandas DataFrame when pandas is importable, the list of dicts otherwise."""
    try:
        import pandas
    except ImportError:
        return rows
    return pandas.DataFrame(rows)
