#!/bin/bash
# Renders MODEL's views on a Slurm cluster, one shard of them per array task, into one shared folder
# (docs/many-views.md). Each task renders the views whose index is its shard modulo the task count
# and writes its own manifest part; after the array, one command merges the parts:
#
#   sbatch docs/slurm-views.sh
#   vkray manifest merge "$OUT"/manifest-shard-*-of-*.jsonl -o "$OUT"/manifest.jsonl
#
# Options of `vkray render` after the script's name (and a "--") go to every task, in place of the
# defaults below for what they set (the views, the size, -o):
#
#   sbatch docs/slurm-views.sh -- --sphere 200 --aov depth,planar-depth --width 1024 --height 1024
#
# Each task renders shard SLURM_ARRAY_TASK_ID of SHARDS (4, as --array=0-3 below: change both
# together), so one task run again alone (sbatch --array=2 docs/slurm-views.sh) renders its own shard,
# not every view. A task that is requeued or run again renders only the views it has not finished. The settings
# below may also be given in the environment (sbatch --export). VKRAY is the relocatable bundle's
# bin/vkray unpacked on the shared file system (docs/install.md, "Installing on a GPU server"), e.g.
# VKRAY=$HOME/vkray-0.1.0-linux-x86_64/bin/vkray; add #SBATCH --gpus=1 on GPU partitions.
#SBATCH --job-name=vkray-views
#SBATCH --array=0-3
#SBATCH --cpus-per-task=2
#SBATCH --output=vkray-views-%a.log
set -eu
VKRAY="${VKRAY:-vkray}"
MODEL="${MODEL-models/stanford-bunny.obj}"
OUT="${OUT:-views}"
VIEWS="${VIEWS:-100}"
SHARDS="${SHARDS:-4}"
WIDTH="${WIDTH:-1920}"
HEIGHT="${HEIGHT:-1080}"
if [ "${1-}" = "--" ]; then shift; fi
options=("$@")
given() {
  local option name
  for option in "${options[@]}"; do
    for name in "$@"; do
      case "$option" in "$name" | "$name"=*) return 0 ;; esac
    done
  done
  return 1
}
defaults=()
given --orbit --sphere --views || defaults+=(--orbit "$VIEWS")
given --width || defaults+=(--width "$WIDTH")
given --height || defaults+=(--height "$HEIGHT")
given -o --output || defaults+=(-o "$OUT/view-{index:05}.exr")
exec "$VKRAY" render "$MODEL" "${defaults[@]}" "${options[@]}" --shard "$SLURM_ARRAY_TASK_ID/$SHARDS"
