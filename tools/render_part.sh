#!/usr/bin/env bash
# Renders one part of a frame for a farm's job array (docs/farm.md): part
# INDEX of COUNT takes the passes INDEX*SPP/COUNT .. (INDEX+1)*SPP/COUNT of
# the frame's seeded sequence and writes OUT_DIR/part-INDEX.fspart. Run it
# again after a preemption or a --time-limit stop and it continues the part
# it left (fspec render --resume); a finished part is left as it is. When
# every index has run, `fspec merge OUT_DIR/part-*.fspart --out frame.exr`
# gives the frame.
#
#   tools/render_part.sh INDEX COUNT SPP OUT_DIR SCENE [fspec render options]
#
# Slurm:       sbatch --array=0-15 --wrap 'tools/render_part.sh "$SLURM_ARRAY_TASK_ID" 16 4096 parts scene.xml'
# Kubernetes:  an Indexed Job whose pods run
#              tools/render_part.sh "$JOB_COMPLETION_INDEX" 16 4096 /parts scene.xml
# GNU parallel: parallel tools/render_part.sh {} 16 4096 parts scene.xml ::: $(seq 0 15)
#
# FSPEC names the fspec binary (default: fspec on the PATH).
set -euo pipefail

if [ "$#" -lt 5 ]; then
  echo "usage: $0 INDEX COUNT SPP OUT_DIR SCENE [fspec render options]" >&2
  exit 2
fi
index=$1 count=$2 spp=$3 out_dir=$4
shift 4
for value in "$index" "$count" "$spp"; do
  case $value in
    '' | *[!0-9]*) echo "$0: INDEX, COUNT and SPP must be whole numbers, got '$value'" >&2; exit 2 ;;
  esac
done
if [ "$count" -lt 1 ] || [ "$index" -ge "$count" ]; then
  echo "$0: INDEX must be below COUNT (got $index of $count)" >&2
  exit 2
fi
first=$(( index * spp / count ))
end=$(( (index + 1) * spp / count ))
if [ "$first" -eq "$end" ]; then
  echo "$0: part $index of $count has no pass ($spp passes in all)"
  exit 0
fi
mkdir -p "$out_dir"
part="$out_dir/part-$index.fspart"
resume=()
if [ -f "$part" ]; then
  resume=(--resume "$part")
fi
exec "${FSPEC:-fspec}" render "$@" --passes "$first..$end" "${resume[@]}" --out "$part" --quiet
