#!/usr/bin/env bash
# The GPU figures of docs/PERFORMANCE.md ("On a GPU"): bench.timings.scaling per env, one block of seeds per
# device, then one seed at a time for contrast. Logs and JSON go to $OUT (default bench/gpu_out), each
# rewritten as rows are measured, so a run cut short keeps what it measured.
#     bash bench/gpu.sh            # PYTHON=python3.11 bash bench/gpu.sh to pick the interpreter
set -u
out=${OUT:-bench/gpu_out}
mkdir -p "$out"
export PYTHONUNBUFFERED=1 PYTHONPATH="$(cd "$(dirname "$0")/.." && pwd)${PYTHONPATH:+:$PYTHONPATH}"
py=${PYTHON:-python3}
{ nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv
  $py -c "import jax, flax, optax; print('jax', jax.__version__, 'flax', flax.__version__, 'optax', optax.__version__, jax.devices())"
} 2>&1 | tee "$out/gpu.txt"
scale() { name=$1; shift; $py -m bench.timings.scaling "$@" --json "$out/$name.json" 2>&1 | tee "$out/$name.log"; }
scale scaling_lsd --env light_switch_door --seed-counts 8,64,256,1024 --cycles 3
scale scaling_doorknobs --env doorknobs --seed-counts 8,64 --cycles 3
scale scaling_lsd_block1 --env light_switch_door --seed-counts 8 --seed-block 1 --cycles 2
# A sweep's settings are more slots of the same program: 4 learning-rate/epsilon settings x 64 seeds, blocks of 64.
{ start=$(date +%s)
  $py train.py --env light_switch_door --approaches ours --num-seeds 64 --seed-block 64 --cycles 3 --no-progress \
      --sweep learning_rate=1e-3,3e-4 --sweep epsilon_decay=3.8e-5,1e-4 --out "${RUNS:-/tmp/gpu_runs}" --name sweep --overwrite
  echo "sweep 4 settings x 64 seeds x 3 cycles: $(( $(date +%s) - start )) s"
} 2>&1 | tee "$out/sweep.log"
