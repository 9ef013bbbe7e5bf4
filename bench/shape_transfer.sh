#!/usr/bin/env bash
# bench/shape_transfer.sh: the paper's last step through the platform. Only the retract
# expert (with its gripper closure) is fine-tuned for a new shape (cylinder, small_block),
# starting from the block hierarchy's retract checkpoint, on the retract training service;
# then every shape is played on the simulated Panda controller (pnp-robot-sim, lockstep)
# through the robot gateway, with the inference service serving the promoted checkpoints.
#
#   1. block hierarchy: `pnpctl pipeline --robot panda --hidden 64 64` on the services
#      (approach, manipulate, retract chained, then the choreographer; each promoted);
#   2. per new shape: `pnpctl train --role retract --object SHAPE --parent <block retract>
#      --prefix <approach> <manipulate>` (fixed seed, target 0.95 twice over 100 evaluation
#      episodes, step cap): env steps to the target (or the cap) and wall time;
#   3. per shape, 100 gateway episodes on `pnp-robot-sim --object SHAPE --clock lockstep`:
#        (a) fine-tuned: the block approach/manipulate/choreographer + the shape's fine-tuned
#            retract promoted (the served object, hence the grasp predicate's width, is the
#            shape: core/serving/served_hierarchy.cpp takes it from the retract checkpoint);
#        (b) not fine-tuned: the block hierarchy as it is (block retract promoted, so the
#            served object is block: the choreographer's grasp predicate uses the block's
#            5 cm width on the smaller shape). For block, (a) = (b).
#      Beside each gateway cell, the same served hierarchy on 100 simulation-service
#      episodes (`pnpctl evaluate`, sim + inference) as an in-simulation reference;
#   4. prints a markdown table and writes $RUN_DIR/shape_transfer.json (every figure,
#      seeds, commands). Per-episode gateway logs: $RUN_DIR/gateway/*.log (JSON lines).
#
# Usage: nice -n 5 bench/shape_transfer.sh
# Environment (defaults): RUN_DIR (a new /tmp/pnp-shape-transfer.XXXXXX), BIN_DIR
# (build/bin; copied into $RUN_DIR/bin so a concurrent rebuild cannot swap a binary
# mid-run), TRAIN_SEED (1), GATEWAY_SEED (880000: episodes 880000..+EPISODES-1),
# SIM_EVAL_SEED (890000), EPISODES (100), FT_MAX_STEPS (30000), FT_TARGET (0.95),
# FT_EVAL_EPISODES (100), BLOCK_MAX_STEPS (30000), HLC_MAX_STEPS (20000),
# BLOCK_EVAL_EPISODES (100), SIM_REFERENCE (1: also run the pnpctl evaluate references).
set -Eeuo pipefail
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$repo"
script_start=$(date +%s.%N)

run_dir=${RUN_DIR:-$(mktemp -d "${TMPDIR:-/tmp}/pnp-shape-transfer.XXXXXX")}
mkdir -p "$run_dir"
run_dir=$(cd "$run_dir" && pwd)
train_seed=${TRAIN_SEED:-1}
gateway_seed=${GATEWAY_SEED:-880000}
sim_eval_seed=${SIM_EVAL_SEED:-890000}
episodes=${EPISODES:-100}
ft_max_steps=${FT_MAX_STEPS:-30000}
ft_target=${FT_TARGET:-0.95}
ft_eval_episodes=${FT_EVAL_EPISODES:-100}
block_max_steps=${BLOCK_MAX_STEPS:-30000}
hlc_max_steps=${HLC_MAX_STEPS:-20000}
block_eval_episodes=${BLOCK_EVAL_EPISODES:-100}
sim_reference=${SIM_REFERENCE:-1}
hidden=(64 64)
shapes=(block cylinder small_block)
new_shapes=(cylinder small_block)
gateway_config=deploy/robot/gateway.json

for tool in jq; do
  command -v "$tool" >/dev/null || { echo "shape_transfer: needs $tool" >&2; exit 1; }
done
if ((gateway_seed < 880000)); then
  echo "shape_transfer: GATEWAY_SEED $gateway_seed: use held-out seeds (>= 880000)" >&2
  exit 1
fi

# A snapshot of the binaries: other work may rebuild build/bin while this runs.
src_bin=${BIN_DIR:-build/bin}
bin="$run_dir/bin"
mkdir -p "$bin" "$run_dir/logs" "$run_dir/gateway" "$run_dir/finetune" "$run_dir/sim_eval"
for b in pnp-sim-server pnp-train-server pnp-inference-server pnp-robot-sim pnp-robot-gateway \
  pnpctl; do
  [[ -x "$src_bin/$b" ]] || { echo "shape_transfer: $src_bin/$b missing: build it" >&2; exit 1; }
  cp "$src_bin/$b" "$bin/$b"
done
db="$run_dir/pnp.db"
rm -f "$db" "$db-wal" "$db-shm"
commands_file="$run_dir/commands.txt"
: >"$commands_file"

pids=()
stop_services() {
  trap - EXIT INT TERM
  ((${#pids[@]})) || return 0
  kill -TERM "${pids[@]}" 2>/dev/null || true
  wait "${pids[@]}" 2>/dev/null || true
}
trap stop_services EXIT
trap 'echo "shape_transfer: failed (exit $?) at line $LINENO: $BASH_COMMAND" >&2' ERR
trap 'exit 130' INT TERM

# record CMD...: appends the command, shell-quoted, to commands.txt.
record() {
  local line
  printf -v line '%q ' "$@"
  echo "${line% }" >>"$commands_file"
}
# logged CMD...: records it, then runs it.
logged() {
  record "$@"
  "$@"
}

# start NAME BINARY ARGS...: listens on a free loopback port, which the server prints as
# its first line of stdout; sets $address and $started_pid. Logs: $run_dir/logs/NAME.log.
address=
started_pid=
start() {
  local name=$1
  shift
  local port_file="$run_dir/logs/$name.port"
  rm -f "$port_file"
  record "$@" --address 127.0.0.1:0
  "$@" --address 127.0.0.1:0 >"$port_file" 2>"$run_dir/logs/$name.log" &
  started_pid=$!
  pids+=("$started_pid")
  for _ in $(seq 400); do
    [[ -s "$port_file" ]] && break
    kill -0 "$started_pid" 2>/dev/null || {
      echo "$name failed to start:" >&2
      cat "$run_dir/logs/$name.log" >&2
      exit 1
    }
    sleep 0.05
  done
  [[ -s "$port_file" ]] || { echo "$name did not print its port" >&2; exit 1; }
  address="127.0.0.1:$(head -n1 "$port_file")"
}

# stop PID: ends one process this script started (SIGTERM: it drains and exits).
stop() {
  local pid=$1 kept=() p
  kill -TERM "$pid" 2>/dev/null || true
  wait "$pid" 2>/dev/null || true
  for p in "${pids[@]}"; do [[ "$p" == "$pid" ]] || kept+=("$p"); done
  pids=("${kept[@]}")
}

now() { date +%s.%N; }
elapsed() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.1f", b - a }'; }

echo "shape_transfer: run dir $run_dir"
start sim "$bin/pnp-sim-server"
sim=$address
endpoints=(--sim "$sim")
for role in approach manipulate retract hlc; do
  start "$role" "$bin/pnp-train-server" --role "$role" --db "$db"
  endpoints+=("--$role" "$address")
done
start inference "$bin/pnp-inference-server" --db "$db" --reload-ms 200
inference=$address
endpoints+=(--inference "$inference")
pnpctl=("$bin/pnpctl" "${endpoints[@]}")
echo "services: sim $sim, inference $inference (logs in $run_dir/logs)"

# ---- 1. the block hierarchy, trained and promoted through the services ----------------
echo
echo "[1] block hierarchy: pnpctl pipeline --robot panda --hidden ${hidden[*]} (seed $train_seed)"
t=$(now)
logged "${pnpctl[@]}" pipeline --robot panda --object block --seed "$train_seed" \
  --hidden "${hidden[@]}" --max-steps "$block_max_steps" --hlc-max-steps "$hlc_max_steps" \
  --target-success "$ft_target" --eval-episodes "$block_eval_episodes" \
  --held-out-episodes "$episodes" --held-out-seed "$sim_eval_seed" --quiet \
  --json-out "$run_dir/block_pipeline.json" | tee "$run_dir/block_pipeline.txt"
block_wall=$(elapsed "$t")
ckpt_of() { jq -r --arg r "$1" '.roles[] | select(.role == $r) | .checkpoint_id' \
  "$run_dir/block_pipeline.json"; }
approach_ckpt=$(ckpt_of approach)
manipulate_ckpt=$(ckpt_of manipulate)
block_retract_ckpt=$(ckpt_of retract)
hlc_ckpt=$(ckpt_of hlc)
echo "block hierarchy: approach $approach_ckpt, manipulate $manipulate_ckpt," \
  "retract $block_retract_ckpt, choreographer $hlc_ckpt ($block_wall s)"

# ---- 2. fine-tune retract per new shape, from the block retract -----------------------
declare -A ft_run ft_ckpt ft_steps ft_reached ft_to_target ft_success ft_wall ft_curve_wall
for shape in "${new_shapes[@]}"; do
  echo
  echo "[2] fine-tune retract for $shape from block retract checkpoint $block_retract_ckpt"
  t=$(now)
  out="$run_dir/finetune/$shape.txt"
  logged "${pnpctl[@]}" train --role retract --robot panda --object "$shape" \
    --seed "$train_seed" --hidden "${hidden[@]}" --max-steps "$ft_max_steps" \
    --target-success "$ft_target" --eval-episodes "$ft_eval_episodes" \
    --parent "$block_retract_ckpt" --prefix "$approach_ckpt" "$manipulate_ckpt" --quiet \
    | tee "$out"
  ft_wall[$shape]=$(elapsed "$t")
  run_id=$(sed -n 's/^run \([0-9]*\) created.*/\1/p' "$out")
  "${pnpctl[@]}" runs --role retract --csv --limit 100 >"$run_dir/finetune/runs.csv"
  row=$(awk -F, -v id="$run_id" 'NR > 1 && $1 == id' "$run_dir/finetune/runs.csv")
  IFS=, read -r _ _ _ _ state steps success reached to_target ckpt _ <<<"$row"
  [[ "$state" == succeeded ]] || { echo "fine-tune run $run_id ended $state" >&2; exit 1; }
  "${pnpctl[@]}" metrics --via retract --csv "$run_id" >"$run_dir/finetune/$shape.curve.csv"
  ft_run[$shape]=$run_id
  ft_ckpt[$shape]=$ckpt
  ft_steps[$shape]=$steps
  ft_success[$shape]=$success
  ft_reached[$shape]=$reached
  ft_to_target[$shape]=$to_target
  ft_curve_wall[$shape]=$(tail -n1 "$run_dir/finetune/$shape.curve.csv" | cut -d, -f3)
done

# ---- 3. gateway episodes per (shape, configuration) -----------------------------------
# promote_retract CKPT: serves the block approach/manipulate/choreographer with this
# retract (PromoteCheckpoint reloads the served hierarchy before it returns).
promote_retract() {
  logged "${pnpctl[@]}" promote "$1" >/dev/null
}

declare -A gw_success gw_rate gw_ends gw_trivial sim_success sim_rate
# cell SHAPE CONFIG: 100 gateway episodes on a fresh pnp-robot-sim with SHAPE; and the
# simulation-service reference for the same served hierarchy.
cell() {
  local shape=$1 config=$2 key="$1/$2"
  start "robot_sim_${shape}_$config" "$bin/pnp-robot-sim" --object "$shape" --clock lockstep
  local robot_sim_pid=$started_pid controller=$address
  local json="$run_dir/gateway/${shape}_$config.json"
  # Not --quiet: the per-episode events (episode_start/episode_end, refusals, dead-man)
  # go to the log as JSON lines.
  if ! logged "$bin/pnp-robot-gateway" --controller "$controller" --inference "$inference" \
    --config "$gateway_config" --episodes "$episodes" --seed "$gateway_seed" --json \
    >"$json" 2>"$run_dir/gateway/${shape}_$config.log"; then
    echo "shape_transfer: the gateway failed on $key:" >&2
    tail -n 3 "$run_dir/gateway/${shape}_$config.log" >&2
    exit 1
  fi
  stop "$robot_sim_pid"
  gw_success[$key]=$(jq .successes "$json")
  gw_rate[$key]=$(jq .success_rate "$json")
  gw_ends[$key]=$(jq -c .ends "$json")
  # Per episode, from the log: seed, success, how it ended, steps. An episode whose scene
  # starts with the object already within the success distance of the goal ends at step 0
  # as a success (the gateway judges success every cycle; the simulation at the episode's end).
  grep '"event":"episode_end"' "$run_dir/gateway/${shape}_$config.log" |
    jq -s '[.[] | {seed, success, end: .["end"], steps, refused, controller_refused}]' \
      >"$run_dir/gateway/${shape}_$config.episodes.json"
  gw_trivial[$key]=$(jq '[.[] | select(.success and .steps == 0)] | length' \
    "$run_dir/gateway/${shape}_$config.episodes.json")
  if ((sim_reference)); then
    local sjson="$run_dir/sim_eval/${shape}_$config.json"
    logged "${pnpctl[@]}" evaluate --robot panda --object "$shape" --episodes "$episodes" \
      --seed "$sim_eval_seed" --json >"$sjson"
    sim_success[$key]=$(jq .successes "$sjson")
    sim_rate[$key]=$(jq .success_rate "$sjson")
  fi
  printf '  %-12s %-13s gateway %3d/%d (%d at step 0)  ends %s' "$shape" "$config" \
    "${gw_success[$key]}" "$episodes" "${gw_trivial[$key]}" "${gw_ends[$key]}"
  if ((sim_reference)); then printf '   sim-service %3d/%d' "${sim_success[$key]}" "$episodes"; fi
  printf '\n'
}

echo
echo "[3] gateway episodes ($episodes per cell, seeds $gateway_seed..$((gateway_seed + episodes - 1)))"
eval_start=$(now)
promote_retract "$block_retract_ckpt"
for shape in "${shapes[@]}"; do cell "$shape" no_finetune; done
for shape in "${new_shapes[@]}"; do
  promote_retract "${ft_ckpt[$shape]}"
  cell "$shape" finetuned
done
promote_retract "$block_retract_ckpt"  # leave the store serving the block hierarchy
eval_wall=$(elapsed "$eval_start")

# ---- 4. table and JSON -----------------------------------------------------------------
total_wall=$(elapsed "$script_start")
pct() { awk -v s="$1" -v n="$episodes" 'BEGIN { printf "%.0f%% (%d/%d)", 100 * s / n, s, n }'; }
table="$run_dir/shape_transfer.md"
{
  echo "| shape | retract served | fine-tune env steps | fine-tune wall | gateway success, no fine-tune (b) | gateway success, fine-tuned (a) | sim-service success (b) | sim-service success (a) |"
  echo "|---|---|---|---|---|---|---|---|"
  for shape in "${shapes[@]}"; do
    if [[ "$shape" == block ]]; then
      b=$(pct "${gw_success[block/no_finetune]}")
      sb=-; [[ -n "${sim_success[block/no_finetune]:-}" ]] && sb=$(pct "${sim_success[block/no_finetune]}")
      echo "| block | block ($block_retract_ckpt) | - (trained on block) | - | $b | $b (= b) | $sb | $sb (= b) |"
    else
      steps="${ft_to_target[$shape]}"
      [[ "$steps" == - ]] && steps="${ft_steps[$shape]} (cap, not reached)"
      sb=-; sa=-
      [[ -n "${sim_success[$shape/no_finetune]:-}" ]] && sb=$(pct "${sim_success[$shape/no_finetune]}")
      [[ -n "${sim_success[$shape/finetuned]:-}" ]] && sa=$(pct "${sim_success[$shape/finetuned]}")
      echo "| $shape | (b) block ($block_retract_ckpt), (a) $shape (${ft_ckpt[$shape]}) | $steps | ${ft_wall[$shape]} s | $(pct "${gw_success[$shape/no_finetune]}") | $(pct "${gw_success[$shape/finetuned]}") | $sb | $sa |"
    fi
  done
} >"$table"

cells_json=$(for key in "${!gw_success[@]}"; do
  jq -n --arg key "$key" --slurpfile g "$run_dir/gateway/${key/\//_}.json" \
    --arg sim "${sim_success[$key]:-}" --argjson n "$episodes" \
    --slurpfile per_episode "$run_dir/gateway/${key/\//_}.episodes.json" \
    --argjson trivial "${gw_trivial[$key]}" \
    '{shape: ($key | split("/")[0]), config: ($key | split("/")[1]), gateway: $g[0],
      gateway_successes_at_step_0: $trivial, gateway_episodes: $per_episode[0],
      gateway_log: ("gateway/" + ($key | sub("/"; "_")) + ".log"),
      sim_service: (if $sim == "" then null else {successes: ($sim | tonumber),
                    success_rate: (($sim | tonumber) / $n)} end)}'
done | jq -s 'sort_by(.shape, .config)')
ft_json=$(for shape in "${new_shapes[@]}"; do
  jq -n --arg shape "$shape" --argjson run "${ft_run[$shape]}" --argjson ckpt "${ft_ckpt[$shape]}" \
    --argjson steps "${ft_steps[$shape]}" --arg reached "${ft_reached[$shape]}" \
    --arg to_target "${ft_to_target[$shape]}" --argjson success "${ft_success[$shape]}" \
    --argjson wall "${ft_wall[$shape]}" --argjson curve_wall "${ft_curve_wall[$shape]}" \
    '{shape: $shape, run_id: $run, checkpoint_id: $ckpt, env_steps: $steps,
      reached: ($reached == "yes"),
      steps_to_target: (if $to_target == "-" then null else ($to_target | tonumber) end),
      steps_counted: (if $to_target == "-" then $steps else ($to_target | tonumber) end),
      final_success: $success, wall_s: $wall, trainer_wall_s: $curve_wall,
      curve: ("finetune/" + $shape + ".curve.csv")}'
done | jq -s .)
jq -n \
  --arg run_dir "$run_dir" --arg commit "$(git rev-parse HEAD 2>/dev/null || echo unknown)" \
  --arg dirty "$(git status --porcelain 2>/dev/null | wc -l)" \
  --argjson train_seed "$train_seed" --argjson gateway_seed "$gateway_seed" \
  --argjson sim_eval_seed "$sim_eval_seed" --argjson episodes "$episodes" \
  --argjson ft_max_steps "$ft_max_steps" --argjson ft_target "$ft_target" \
  --argjson ft_eval_episodes "$ft_eval_episodes" --argjson block_max_steps "$block_max_steps" \
  --argjson hlc_max_steps "$hlc_max_steps" --argjson block_eval_episodes "$block_eval_episodes" \
  --slurpfile block "$run_dir/block_pipeline.json" \
  --argjson block_wall "$block_wall" --argjson eval_wall "$eval_wall" \
  --argjson total_wall "$total_wall" \
  --argjson ckpts "{\"approach\": $approach_ckpt, \"manipulate\": $manipulate_ckpt, \"retract\": $block_retract_ckpt, \"hlc\": $hlc_ckpt}" \
  --argjson finetunes "$ft_json" --argjson cells "$cells_json" \
  --rawfile commands "$commands_file" --rawfile table "$table" \
  '{run_dir: $run_dir, code_commit: $commit, uncommitted_files: ($dirty | tonumber),
    robot: "panda", hidden: [64, 64],
    seeds: {training: $train_seed,
            gateway_first: $gateway_seed, gateway_last: ($gateway_seed + $episodes - 1),
            sim_service_evaluation: $sim_eval_seed},
    settings: {episodes_per_cell: $episodes, finetune_max_steps: $ft_max_steps,
               target_success: $ft_target, finetune_eval_episodes: $ft_eval_episodes,
               block_expert_max_steps: $block_max_steps, block_hlc_max_steps: $hlc_max_steps,
               block_eval_episodes: $block_eval_episodes,
               gateway_config: "deploy/robot/gateway.json", robot_sim_clock: "lockstep"},
    configurations: {
      finetuned: "block approach, manipulate and choreographer + the shape fine-tuned retract; served object (grasp width) = the shape",
      no_finetune: "the block hierarchy unchanged (block retract promoted); served object (grasp width) = block"},
    block_hierarchy: {checkpoints: $ckpts, pipeline: $block[0], wall_s: $block_wall},
    finetunes: $finetunes, cells: $cells,
    wall_s: {total: $total_wall, block_pipeline: $block_wall, evaluation: $eval_wall},
    commands: ($commands | rtrimstr("\n") | split("\n")),
    table_markdown: $table}' >"$run_dir/shape_transfer.json"

echo
echo "Shape transfer (Panda; $episodes gateway episodes per cell, seeds $gateway_seed..$((gateway_seed + episodes - 1)); training seed $train_seed)"
echo
cat "$table"
echo
echo "Gateway successes at step 0 (the scene starts with the object within the success"
echo "distance of the goal; the gateway stops there, the simulation judges the episode's end):"
for key in "${!gw_trivial[@]}"; do echo "  $key: ${gw_trivial[$key]}"; done | sort
echo "whole script: $total_wall s (block pipeline $block_wall s, evaluation $eval_wall s)"
echo "JSON: $run_dir/shape_transfer.json; gateway logs: $run_dir/gateway/"
