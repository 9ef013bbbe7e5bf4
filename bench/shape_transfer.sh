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
#   (c) end-to-end: the end-to-end DDPG+HER baseline (one actor for the whole task), trained
#      on block through the e2e training service (`pnpctl train --role e2e --robot panda
#      --object block`, step cap E2E_MAX_STEPS, target 0.95 twice over 100 evaluation
#      episodes), its latest checkpoint promoted and served by a second inference service
#      (`pnp-inference-server --policy e2e`, same store); then per shape 100 gateway
#      episodes on a fresh `pnp-robot-sim --object SHAPE --clock lockstep` against it
#      (cells with config "e2e"), plus the same sim-service reference;
#   4. prints a markdown table and writes $RUN_DIR/shape_transfer.json (every figure,
#      seeds, commands). Per-episode gateway logs: $RUN_DIR/gateway/*.log (JSON lines).
#
# E2E_ONLY=1 runs only the end-to-end part (column (c)) against a fresh store (no block
# hierarchy, no fine-tuning). With MERGE_INTO=<a full run's shape_transfer.json> (same
# gateway seeds and episodes) it then writes shape_transfer_with_e2e.json (that JSON with
# the e2e cells and training added) and shape_transfer_with_e2e.md (the combined table)
# beside it; the originals are left unchanged.
#
# Usage: nice -n 5 bench/shape_transfer.sh
#        E2E_ONLY=1 RUN_DIR=/tmp/st-e2e MERGE_INTO=/tmp/st-full/shape_transfer.json \
#          nice -n 5 bench/shape_transfer.sh
# Environment (defaults): RUN_DIR (a new /tmp/pnp-shape-transfer.XXXXXX), BIN_DIR
# (build/bin; copied into $RUN_DIR/bin so a concurrent rebuild cannot swap a binary
# mid-run), TRAIN_SEED (1), GATEWAY_SEED (880000: episodes 880000..+EPISODES-1),
# SIM_EVAL_SEED (890000), EPISODES (100), FT_MAX_STEPS (30000), FT_TARGET (0.95),
# FT_EVAL_EPISODES (100), BLOCK_MAX_STEPS (30000), HLC_MAX_STEPS (20000),
# BLOCK_EVAL_EPISODES (100), SIM_REFERENCE (1: also run the pnpctl evaluate references),
# E2E (1: also column (c)), E2E_ONLY (0), E2E_MAX_STEPS (100000), E2E_TARGET (0.95),
# E2E_EVAL_INTERVAL (5000), E2E_EVAL_EPISODES (100), E2E_HIDDEN (empty: the service's
# DDPG default, 256 256 256), MERGE_INTO (empty; with E2E_ONLY, see above).
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
e2e_only=${E2E_ONLY:-0}
e2e=${E2E:-1}
((e2e_only)) && e2e=1
e2e_max_steps=${E2E_MAX_STEPS:-100000}
e2e_target=${E2E_TARGET:-0.95}
e2e_eval_interval=${E2E_EVAL_INTERVAL:-5000}
e2e_eval_episodes=${E2E_EVAL_EPISODES:-100}
read -r -a e2e_hidden <<<"${E2E_HIDDEN:-}"
merge_into=${MERGE_INTO:-}
e2e_reuse=${E2E_REUSE:-0}
if ((e2e_reuse)); then
  ((e2e_only)) && [[ -n "${RUN_DIR:-}" && -f "$RUN_DIR/pnp.db" ]] || {
    echo "shape_transfer: E2E_REUSE=1 needs E2E_ONLY=1 and a RUN_DIR with a pnp.db" >&2
    exit 1
  }
fi
if [[ -n "$merge_into" ]]; then
  ((e2e_only)) || { echo "shape_transfer: MERGE_INTO needs E2E_ONLY=1" >&2; exit 1; }
  [[ -f "$merge_into" ]] || { echo "shape_transfer: MERGE_INTO $merge_into: no such file" >&2; exit 1; }
  merge_into=$(cd "$(dirname "$merge_into")" && pwd)/$(basename "$merge_into")
  base_seed=$(jq .seeds.gateway_first "$merge_into")
  base_episodes=$(jq .settings.episodes_per_cell "$merge_into")
  if [[ "$base_seed" != "${GATEWAY_SEED:-880000}" || "$base_episodes" != "${EPISODES:-100}" ]]; then
    echo "shape_transfer: MERGE_INTO has gateway seeds $base_seed.., $base_episodes episodes per cell:" \
      "run with the same GATEWAY_SEED and EPISODES" >&2
    exit 1
  fi
fi
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
  ((e2e_reuse)) && [[ -x "$bin/$b" ]] && continue  # the first run's snapshot
  [[ -x "$src_bin/$b" ]] || { echo "shape_transfer: $src_bin/$b missing: build it" >&2; exit 1; }
  cp "$src_bin/$b" "$bin/$b"
done
db="$run_dir/pnp.db"
commands_file="$run_dir/commands.txt"
if ((e2e_reuse)); then
  echo "# E2E_REUSE=1: the store's e2e run reused, not retrained" >>"$commands_file"
else
  rm -f "$db" "$db-wal" "$db-shm"
  : >"$commands_file"
fi

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
training_roles=(approach manipulate retract hlc)
((e2e_only)) && training_roles=()
((e2e)) && training_roles+=(e2e)
for role in "${training_roles[@]}"; do
  start "$role" "$bin/pnp-train-server" --role "$role" --db "$db"
  endpoints+=("--$role" "$address")
done
inference=
if ! ((e2e_only)); then
  start inference "$bin/pnp-inference-server" --db "$db" --reload-ms 200
  inference=$address
  endpoints+=(--inference "$inference")
fi
pnpctl=("$bin/pnpctl" "${endpoints[@]}")
echo "services: sim $sim, training ${training_roles[*]}, inference ${inference:-(e2e only: later)}" \
  "(logs in $run_dir/logs)"

declare -A gw_success gw_rate gw_ends gw_trivial sim_success sim_rate
# cell SHAPE CONFIG [INFERENCE]: 100 gateway episodes on a fresh pnp-robot-sim with SHAPE,
# driven by the policy the inference service INFERENCE (default: the hierarchy's) serves;
# and the simulation-service reference for the same served policy.
cell() {
  local shape=$1 config=$2 key="$1/$2" inf=${3:-$inference}
  local json="$run_dir/gateway/${shape}_$config.json" log="$run_dir/gateway/${shape}_$config.log"
  local segments="$run_dir/gateway/${shape}_$config.segments.jsonl"
  local next=$gateway_seed last=$((gateway_seed + episodes - 1)) segment=0 seg_log seg_json
  : >"$log"
  : >"$segments"
  # The gateway stops at the first controller report it refuses (e.g. a finger gap below
  # -5 mm: the end-to-end policy squeezes the empty gripper harder than the hierarchy's
  # scripted closure). Such an episode counts as a failure ("gateway_error") and the
  # remaining seeds run in a new segment: a fresh pnp-robot-sim and gateway. Without a
  # refusal this is one gateway run over all the seeds, as before.
  while ((next <= last)); do
    start "robot_sim_${shape}_${config}_$segment" "$bin/pnp-robot-sim" --object "$shape" \
      --clock lockstep
    local robot_sim_pid=$started_pid controller=$address
    seg_log="$run_dir/gateway/${shape}_$config.$segment.log"
    seg_json="$run_dir/gateway/${shape}_$config.$segment.json"
    # Not --quiet: the per-episode events (episode_start/episode_end, refusals, dead-man)
    # go to the log as JSON lines.
    local rc=0
    logged "$bin/pnp-robot-gateway" --controller "$controller" --inference "$inf" \
      --config "$gateway_config" --episodes "$((last - next + 1))" --seed "$next" --json \
      >"$seg_json" 2>"$seg_log" || rc=$?
    stop "$robot_sim_pid"
    cat "$seg_log" >>"$log"
    if ((rc == 0)); then
      jq -c --argjson seg "$segment" '{segment: $seg, summary: .}' "$seg_json" >>"$segments"
      break
    fi
    # The episode that was running: the last started without an end.
    local failed error
    failed=$(grep '"event":"episode_start"' "$seg_log" | tail -n1 | jq .seed)
    error=$(grep -v '^{' "$seg_log" | tail -n1 || true)
    if [[ -z "$failed" || "$failed" == null ]] ||
      grep '"event":"episode_end"' "$seg_log" | jq -e --argjson s "$failed" 'select(.seed == $s)' \
        >/dev/null; then
      echo "shape_transfer: the gateway failed on $key outside an episode (exit $rc):" >&2
      tail -n 3 "$seg_log" >&2
      exit 1
    fi
    echo "  $key: gateway stopped in episode $failed: $error (counted as a failure; next segment)"
    jq -cn --argjson seg "$segment" --argjson seed "$failed" --arg error "$error" --argjson rc "$rc" \
      '{segment: $seg, summary: null, exit_code: $rc, error_episode: {seed: $seed, error: $error}}' \
      >>"$segments"
    # The refused report's episode ends here, as a failure, in the cell's log.
    jq -cn --argjson seed "$failed" --arg error "$error" \
      '{event: "episode_end", service: "shape_transfer", seed: $seed, success: false,
        end: "gateway_error", error: $error, steps: null, refused: null, controller_refused: null}' \
      >>"$log"
    next=$((failed + 1))
    segment=$((segment + 1))
  done
  if (($(wc -l <"$segments") == 1)) && [[ "$(head -n1 "$segments" | jq .summary)" != null ]]; then
    head -n1 "$segments" | jq .summary >"$json"  # one clean run: the gateway's own summary
  else
    # Several segments: the cell's summary from the episode ends (each seed once).
    grep '"event":"episode_end"' "$log" | jq -s --argjson n "$episodes" --slurpfile segs "$segments" '
      {episodes: length, successes: (map(select(.success)) | length),
       success_rate: ((map(select(.success)) | length) / $n),
       ends: (group_by(.end) | map({key: .[0].end, value: length}) | from_entries),
       seeds: map(.seed), gateway_errors: [$segs[] | .error_episode | select(. != null)],
       segments: $segs}' >"$json"
    (($(jq .episodes "$json") == episodes)) || {
      echo "shape_transfer: $key: $(jq .episodes "$json") episode ends, expected $episodes" >&2
      exit 1
    }
  fi
  gw_success[$key]=$(jq .successes "$json")
  gw_rate[$key]=$(jq .success_rate "$json")
  gw_ends[$key]=$(jq -c .ends "$json")
  # Per episode, from the log: seed, success, how it ended, steps. An episode whose scene
  # starts with the object already within the success distance of the goal ends at step 0
  # as a success (the gateway judges success every cycle; the simulation at the episode's end).
  grep '"event":"episode_end"' "$log" |
    jq -s '[.[] | {seed, success, end: .["end"], steps, refused, controller_refused}
            + (if .error then {error} else {} end)]' \
      >"$run_dir/gateway/${shape}_$config.episodes.json"
  gw_trivial[$key]=$(jq '[.[] | select(.success and .steps == 0)] | length' \
    "$run_dir/gateway/${shape}_$config.episodes.json")
  if ((sim_reference)); then
    local sjson="$run_dir/sim_eval/${shape}_$config.json"
    logged "$bin/pnpctl" --sim "$sim" --inference "$inf" evaluate --robot panda \
      --object "$shape" --episodes "$episodes" --seed "$sim_eval_seed" --json >"$sjson"
    sim_success[$key]=$(jq .successes "$sjson")
    sim_rate[$key]=$(jq .success_rate "$sjson")
  fi
  printf '  %-12s %-13s gateway %3d/%d (%d at step 0)  ends %s' "$shape" "$config" \
    "${gw_success[$key]}" "$episodes" "${gw_trivial[$key]}" "${gw_ends[$key]}"
  if ((sim_reference)); then printf '   sim-service %3d/%d' "${sim_success[$key]}" "$episodes"; fi
  printf '\n'
}

block_wall=null
eval_wall=null
block_ckpts_json=null
ft_json=null
if ! ((e2e_only)); then
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
block_ckpts_json="{\"approach\": $approach_ckpt, \"manipulate\": $manipulate_ckpt, \"retract\": $block_retract_ckpt, \"hlc\": $hlc_ckpt}"
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
fi  # the hierarchy and its fine-tuning (not with E2E_ONLY=1)

# ---- (c) the end-to-end baseline: trained on block, served by a second inference service
e2e_json=null
e2e_eval_wall=null
if ((e2e)); then
  echo
  echo "[c] end-to-end DDPG+HER on block: pnpctl train --role e2e (seed $train_seed," \
    "cap $e2e_max_steps steps, hidden ${e2e_hidden[*]:-service default})"
  mkdir -p "$run_dir/e2e"
  hidden_args=()
  if ((${#e2e_hidden[@]})); then hidden_args=(--hidden "${e2e_hidden[@]}"); fi
  t=$(now)
  out="$run_dir/e2e/train.txt"
  if ((e2e_reuse)); then
    # E2E_REUSE=1: the run this RUN_DIR's store already holds (its first pass trained it).
    e2e_run=$(sed -n 's/^run \([0-9]*\) created.*/\1/p' "$out")
    e2e_wall=$(cat "$run_dir/e2e/wall_s")
    echo "reusing e2e run $e2e_run ($e2e_wall s when trained)"
  else
    logged "${pnpctl[@]}" train --role e2e --robot panda --object block --seed "$train_seed" \
      "${hidden_args[@]}" --max-steps "$e2e_max_steps" --eval-interval "$e2e_eval_interval" \
      --eval-episodes "$e2e_eval_episodes" --target-success "$e2e_target" --quiet | tee "$out"
    e2e_wall=$(elapsed "$t")
    echo "$e2e_wall" >"$run_dir/e2e/wall_s"
  fi
  "${pnpctl[@]}" runs --role e2e --csv --limit 100 >"$run_dir/e2e/runs.csv"
  row=$(awk -F, -v id="$e2e_run" 'NR > 1 && $1 == id' "$run_dir/e2e/runs.csv")
  IFS=, read -r _ _ _ _ e2e_state e2e_steps e2e_success e2e_reached e2e_to_target e2e_ckpt _ \
    <<<"$row"
  [[ "$e2e_state" == succeeded ]] || { echo "e2e run $e2e_run ended $e2e_state" >&2; exit 1; }
  "${pnpctl[@]}" metrics --via e2e --csv "$e2e_run" >"$run_dir/e2e/curve.csv"
  e2e_curve_wall=$(tail -n1 "$run_dir/e2e/curve.csv" | cut -d, -f3)
  e2e_best=$(awk -F, 'NR > 1 && $4 + 0 > b { b = $4 + 0 } END { printf "%.3f", b + 0 }' \
    "$run_dir/e2e/curve.csv")
  e2e_evaluations=$(($(wc -l <"$run_dir/e2e/curve.csv") - 1))
  # The hierarchy's inference service keeps serving the hierarchy; this one serves the
  # promoted e2e checkpoint (PromoteCheckpoint reloads it before it returns).
  start inference_e2e "$bin/pnp-inference-server" --policy e2e --db "$db" --reload-ms 200
  e2e_inference=$address
  logged "$bin/pnpctl" --inference "$e2e_inference" promote "$e2e_ckpt" | tee "$run_dir/e2e/promote.txt"
  echo "end-to-end: run $e2e_run, $e2e_steps env steps, final evaluation success $e2e_success" \
    "(best $e2e_best), target reached: $e2e_reached, checkpoint $e2e_ckpt ($e2e_wall s);" \
    "served by $e2e_inference"
  echo
  echo "[c] gateway episodes, end-to-end ($episodes per cell, seeds $gateway_seed..$((gateway_seed + episodes - 1)))"
  e2e_eval_start=$(now)
  for shape in "${shapes[@]}"; do cell "$shape" e2e "$e2e_inference"; done
  e2e_eval_wall=$(elapsed "$e2e_eval_start")
  e2e_json=$(jq -n --argjson run "$e2e_run" --argjson ckpt "$e2e_ckpt" \
    --argjson steps "$e2e_steps" --arg reached "$e2e_reached" --arg to_target "$e2e_to_target" \
    --argjson success "$e2e_success" --argjson best "$e2e_best" --argjson wall "$e2e_wall" \
    --argjson curve_wall "$e2e_curve_wall" --argjson evaluations "$e2e_evaluations" \
    --argjson max_steps "$e2e_max_steps" --argjson target "$e2e_target" \
    --argjson eval_interval "$e2e_eval_interval" --argjson eval_episodes "$e2e_eval_episodes" \
    --argjson seed "$train_seed" --arg hidden "${e2e_hidden[*]:-}" \
    --argjson eval_wall "$e2e_eval_wall" --arg run_dir "$run_dir" --argjson reuse "$e2e_reuse" \
    '{trained_on: {robot: "panda", object: "block"}, seed: $seed, algorithm: "ddpg_her",
      hidden: (if $hidden == "" then "service default (256 256 256)"
               else ($hidden | split(" ") | map(tonumber)) end),
      max_steps: $max_steps, target_success: $target, eval_interval_steps: $eval_interval,
      eval_episodes: $eval_episodes, run_id: $run, checkpoint_id: $ckpt, env_steps: $steps,
      reached: ($reached == "yes"),
      steps_to_target: (if $to_target == "-" then null else ($to_target | tonumber) end),
      final_success: $success, best_success: $best, evaluations: $evaluations,
      wall_s: $wall, trainer_wall_s: $curve_wall, gateway_evaluation_wall_s: $eval_wall,
      run_dir: $run_dir, curve: "e2e/curve.csv",
      trained_by_an_earlier_pass: ($reuse == 1),
      served_by: "pnp-inference-server --policy e2e (a second inference service, same store)"}')
fi

# ---- 4. table and JSON -----------------------------------------------------------------
total_wall=$(elapsed "$script_start")
# render_table < shape_transfer.json: the markdown table (hierarchy columns when the JSON
# has the block hierarchy, end-to-end columns when it has the e2e run), then a line on the
# end-to-end training.
render_table() {
  jq -r '
    def pct($n): "\(100 * . / $n | round)% (\(.)/\($n))";
    def f1: (. * 10 | round) as $t | "\($t / 10 | floor).\($t % 10)";
    def row: "| " + join(" | ") + " |";
    .settings.episodes_per_cell as $n
    | (.cells | map({key: "\(.shape)/\(.config)", value: .}) | from_entries) as $c
    | (.shapes // ["block", "cylinder", "small_block"]) as $shapes
    | (.block_hierarchy != null) as $h
    | (.end_to_end != null) as $e
    | .block_hierarchy.checkpoints.retract as $r
    | .end_to_end as $t
    | .finetunes as $ft
    | def gw($k): if $c[$k] then ($c[$k].gateway.successes | pct($n)) else "-" end;
      def sim($k): if $c[$k].sim_service then ($c[$k].sim_service.successes | pct($n)) else "-" end;
      def e2e_cols($s): if $e then [gw("\($s)/e2e"), sim("\($s)/e2e")] else [] end;
      (if $h then
         ["shape", "retract served", "fine-tune env steps", "fine-tune wall",
          "gateway success, no fine-tune (b)", "gateway success, fine-tuned (a)",
          "sim-service success (b)", "sim-service success (a)"]
       else ["shape"] end)
      + (if $e then ["gateway success, end-to-end (c)", "sim-service success (c)"] else [] end)
      | . as $header
      | ($header | row),
        ([$header[] | "---"] | "|" + join("|") + "|"),
        ($shapes[] as $s
         | if $h | not then [$s] + e2e_cols($s)
           elif $s == "block" then
             ["block", "block (\($r))", "- (trained on block)", "-", gw("block/no_finetune"),
              gw("block/no_finetune") + " (= b)", sim("block/no_finetune"),
              sim("block/no_finetune") + " (= b)"] + e2e_cols($s)
           else
             ($ft[] | select(.shape == $s)) as $f
             | [$s, "(b) block (\($r)), (a) \($s) (\($f.checkpoint_id))",
                (if $f.steps_to_target then "\($f.steps_to_target)"
                 else "\($f.env_steps) (cap, not reached)" end),
                "\($f.wall_s | f1) s", gw("\($s)/no_finetune"), gw("\($s)/finetuned"),
                sim("\($s)/no_finetune"), sim("\($s)/finetuned")] + e2e_cols($s)
           end
         | row),
        (if $e then
           "",
           "(c) end-to-end DDPG+HER, trained on block (Panda, seed \($t.seed), hidden \($t.hidden | if type == "array" then map(tostring) | join("x") else . end)) through the e2e training service: \($t.env_steps) env steps (cap \($t.max_steps)), final evaluation success \($t.final_success) (best \($t.best_success) over \($t.evaluations) evaluations of \($t.eval_episodes) episodes), target \($t.target_success) \(if $t.reached then "reached at \($t.steps_to_target) steps" else "not reached" end), \($t.wall_s | f1) s wall; checkpoint \($t.checkpoint_id) served by pnp-inference-server --policy e2e."
         else empty end)'
}

# The cells (large: every episode) go through a file, not an argument.
cells_file="$run_dir/cells.json"
for key in "${!gw_success[@]}"; do
  jq -n --arg key "$key" --slurpfile g "$run_dir/gateway/${key/\//_}.json" \
    --arg sim "${sim_success[$key]:-}" --argjson n "$episodes" \
    --slurpfile per_episode "$run_dir/gateway/${key/\//_}.episodes.json" \
    --argjson trivial "${gw_trivial[$key]}" \
    '{shape: ($key | split("/")[0]), config: ($key | split("/")[1]), gateway: $g[0],
      gateway_successes_at_step_0: $trivial, gateway_episodes: $per_episode[0],
      gateway_log: ("gateway/" + ($key | sub("/"; "_")) + ".log"),
      sim_service: (if $sim == "" then null else {successes: ($sim | tonumber),
                    success_rate: (($sim | tonumber) / $n)} end)}'
done | jq -s 'sort_by(.shape, .config)' >"$cells_file"
block_pipeline=null
[[ -f "$run_dir/block_pipeline.json" ]] && block_pipeline=$(cat "$run_dir/block_pipeline.json")
result="$run_dir/shape_transfer.json"
jq -n \
  --arg run_dir "$run_dir" --arg commit "$(git rev-parse HEAD 2>/dev/null || echo unknown)" \
  --arg dirty "$(git status --porcelain 2>/dev/null | wc -l)" \
  --argjson train_seed "$train_seed" --argjson gateway_seed "$gateway_seed" \
  --argjson sim_eval_seed "$sim_eval_seed" --argjson episodes "$episodes" \
  --argjson ft_max_steps "$ft_max_steps" --argjson ft_target "$ft_target" \
  --argjson ft_eval_episodes "$ft_eval_episodes" --argjson block_max_steps "$block_max_steps" \
  --argjson hlc_max_steps "$hlc_max_steps" --argjson block_eval_episodes "$block_eval_episodes" \
  --argjson e2e_only "$e2e_only" --argjson e2e_max_steps "$e2e_max_steps" \
  --argjson block "$block_pipeline" \
  --argjson block_wall "$block_wall" --argjson eval_wall "$eval_wall" \
  --argjson e2e_eval_wall "$e2e_eval_wall" --argjson total_wall "$total_wall" \
  --argjson ckpts "$block_ckpts_json" --argjson finetunes "$ft_json" \
  --argjson end_to_end "$e2e_json" --slurpfile cells "$cells_file" \
  --rawfile commands "$commands_file" \
  '{run_dir: $run_dir, code_commit: $commit, uncommitted_files: ($dirty | tonumber),
    robot: "panda", hidden: [64, 64], shapes: ["block", "cylinder", "small_block"],
    e2e_only: ($e2e_only == 1),
    seeds: {training: $train_seed,
            gateway_first: $gateway_seed, gateway_last: ($gateway_seed + $episodes - 1),
            sim_service_evaluation: $sim_eval_seed},
    settings: ({episodes_per_cell: $episodes,
                gateway_config: "deploy/robot/gateway.json", robot_sim_clock: "lockstep"}
               + (if $e2e_only == 1 then {} else
                   {finetune_max_steps: $ft_max_steps,
                    target_success: $ft_target, finetune_eval_episodes: $ft_eval_episodes,
                    block_expert_max_steps: $block_max_steps, block_hlc_max_steps: $hlc_max_steps,
                    block_eval_episodes: $block_eval_episodes} end)
               + (if $end_to_end == null then {} else {e2e_max_steps: $e2e_max_steps} end)),
    configurations: ((if $e2e_only == 1 then {} else {
      finetuned: "block approach, manipulate and choreographer + the shape fine-tuned retract; served object (grasp width) = the shape",
      no_finetune: "the block hierarchy unchanged (block retract promoted); served object (grasp width) = block"} end)
      + (if $end_to_end == null then {} else {
      e2e: "the end-to-end DDPG+HER baseline trained on block (one actor for the whole task, learned gripper), served by pnp-inference-server --policy e2e"} end)),
    block_hierarchy: (if $ckpts == null then null
                      else {checkpoints: $ckpts, pipeline: $block, wall_s: $block_wall} end),
    finetunes: $finetunes, end_to_end: $end_to_end, cells: $cells[0],
    wall_s: {total: $total_wall, block_pipeline: $block_wall, evaluation: $eval_wall,
             e2e_training: $end_to_end.wall_s, e2e_evaluation: $e2e_eval_wall},
    commands: ($commands | rtrimstr("\n") | split("\n"))}' >"$result.tmp"
table="$run_dir/shape_transfer.md"
render_table <"$result.tmp" >"$table"
jq --rawfile table "$table" '. + {table_markdown: $table}' "$result.tmp" >"$result"
rm -f "$result.tmp"

echo
echo "Shape transfer (Panda; $episodes gateway episodes per cell, seeds $gateway_seed..$((gateway_seed + episodes - 1)); training seed $train_seed)"
echo
cat "$table"
echo
echo "Gateway successes at step 0 (the scene starts with the object within the success"
echo "distance of the goal; the gateway stops there, the simulation judges the episode's end):"
for key in "${!gw_trivial[@]}"; do echo "  $key: ${gw_trivial[$key]}"; done | sort
echo "whole script: $total_wall s (block pipeline $block_wall s, evaluation $eval_wall s," \
  "e2e training ${e2e_wall:-null} s, e2e evaluation $e2e_eval_wall s)"
echo "JSON: $result; gateway logs: $run_dir/gateway/"

# ---- E2E_ONLY + MERGE_INTO: the e2e cells and training added to a full run's JSON -------
if [[ -n "$merge_into" ]]; then
  merged_json="$(dirname "$merge_into")/shape_transfer_with_e2e.json"
  merged_md="$(dirname "$merge_into")/shape_transfer_with_e2e.md"
  # The e2e cells keep their logs in this run dir: their paths become absolute.
  jq --slurpfile e2e "$result" '
      ($e2e[0].run_dir) as $d
      | .cells = ((.cells | map(select(.config != "e2e")))
                  + [$e2e[0].cells[] | select(.config == "e2e")
                     | .gateway_log = ($d + "/" + .gateway_log)]
                  | sort_by(.shape, .config))
      | .end_to_end = ($e2e[0].end_to_end | .curve = ($d + "/" + .curve))
      | .settings.e2e_max_steps = $e2e[0].settings.e2e_max_steps
      | .configurations.e2e = $e2e[0].configurations.e2e
      | .wall_s.e2e_training = $e2e[0].wall_s.e2e_training
      | .wall_s.e2e_evaluation = $e2e[0].wall_s.e2e_evaluation
      | .wall_s.e2e_run_total = $e2e[0].wall_s.total
      | .e2e_merged_from = {run_dir: $d, code_commit: $e2e[0].code_commit,
                            commands: $e2e[0].commands}' "$merge_into" >"$merged_json.tmp"
  render_table <"$merged_json.tmp" >"$merged_md"
  jq --rawfile table "$merged_md" '. + {table_markdown: $table}' "$merged_json.tmp" >"$merged_json"
  rm -f "$merged_json.tmp"
  echo
  echo "Merged with $merge_into:"
  echo
  cat "$merged_md"
  echo
  echo "JSON: $merged_json; table: $merged_md"
fi
