#!/usr/bin/env bash
# The GPU figures of docs/PERFORMANCE.md ("On a GPU"): bench.scaling per env, one block of seeds per
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
scale() { name=$1; shift; $py -m bench.scaling "$@" --json "$out/$name.json" 2>&1 | tee "$out/$name.log"; }
scale scaling_lsd --env light_switch_door --seeds 8,64,256,1024 --cycles 3
scale scaling_doorknobs --env doorknobs --seeds 8,64 --cycles 3
scale scaling_lsd_block1 --env light_switch_door --seeds 8 --seed-block 1 --cycles 2
