#!/usr/bin/env bash
# Render SCENE on a Slurm cluster: an N-task job array whose tasks render tiles
# (or sample ranges) and a merge job that runs once all of them succeeded.
#
#   scripts/slurm_render.sh SCENE N [--split tiles|samples] [--out DIR] [-- RENDER ARGS...]
#
#   --split tiles    task K renders `--tile K/N` (default)
#   --split samples  task K renders samples ⌊K·S/N⌋..⌊(K+1)·S/N⌋ of S = --spp
#                    (give --spp S among the render args)
#   --out DIR        parts, logs and the merged DIR/<scene>.exr + .png
#                    [default: out/<scene>-slurm]
#
# Environment: GRADTRACE (the binary every node runs, default: the one built in
# this checkout), SBATCH (default `sbatch`), SBATCH_ARGS (extra sbatch options,
# e.g. "--partition=render --time=02:00:00"). The job scripts are written to DIR
# first (render.sbatch, merge.sbatch), so they can be read or resubmitted.
# DIR must be on a file system every node sees.
set -euo pipefail

usage() { sed -n '2,17p' "$0" | sed 's/^# \{0,1\}//'; exit 2; }
[ $# -ge 2 ] || usage
scene=$1 n=$2
shift 2
split=tiles out=""
while [ $# -gt 0 ]; do
    case $1 in
        --split) split=${2:?--split needs tiles or samples}; shift 2 ;;
        --out) out=${2:?--out needs a directory}; shift 2 ;;
        --) shift; break ;;
        *) echo "slurm_render.sh: unknown option $1 (render args go after --)" >&2; exit 2 ;;
    esac
done
case $n in ''|*[!0-9]*|0) echo "slurm_render.sh: N must be a positive integer, got '$n'" >&2; exit 2 ;; esac
[ -f "$scene" ] || { echo "slurm_render.sh: $scene: no such scene file" >&2; exit 2; }

here=$(cd "$(dirname "$0")/.." && pwd)
gradtrace=${GRADTRACE:-$here/target/release/gradtrace}
sbatch=${SBATCH:-sbatch}
stem=$(basename "${scene%.*}")
out=${out:-out/$stem-slurm}
mkdir -p "$out/logs"
scene=$(cd "$(dirname "$scene")" && pwd)/$(basename "$scene")
out=$(cd "$out" && pwd)

# Shell-quoted render arguments, for the job scripts.
render_args=""
for a in "$@"; do render_args+=" $(printf '%q' "$a")"; done

case $split in
    tiles) part='--tile "$K/'"$n"'"' ;;
    samples)
        spp=""
        prev=""
        for a in "$@"; do
            [ "$prev" = "--spp" ] && spp=$a
            case $a in --spp=*) spp=${a#--spp=} ;; esac
            prev=$a
        done
        [ -n "$spp" ] || { echo "slurm_render.sh: --split samples needs --spp S among the render args" >&2; exit 2; }
        [ "$spp" -ge "$n" ] || { echo "slurm_render.sh: --spp $spp is less than N = $n sample ranges" >&2; exit 2; }
        part='--spp-range "$(( K * '"$spp"' / '"$n"' )):$(( (K + 1) * '"$spp"' / '"$n"' ))"' ;;
    *) echo "slurm_render.sh: --split must be tiles or samples, got '$split'" >&2; exit 2 ;;
esac

cat > "$out/render.sbatch" <<EOF
#!/usr/bin/env bash
#SBATCH --job-name=gradtrace-$stem
#SBATCH --output=$out/logs/render-%A_%a.log
set -euo pipefail
K=\$SLURM_ARRAY_TASK_ID
exec $(printf '%q' "$gradtrace") render $(printf '%q' "$scene") $part --quiet --out "$out/part-\$K.exr"$render_args
EOF

parts=""
for ((k = 0; k < n; k++)); do parts+=" $(printf '%q' "$out/part-$k.exr")"; done
cat > "$out/merge.sbatch" <<EOF
#!/usr/bin/env bash
#SBATCH --job-name=gradtrace-$stem-merge
#SBATCH --output=$out/logs/merge-%j.log
set -euo pipefail
exec $(printf '%q' "$gradtrace") merge$parts --out $(printf '%q' "$out/$stem.exr")
EOF

# shellcheck disable=SC2086 # SBATCH_ARGS is a list of options
array=$($sbatch --parsable --array="0-$((n - 1))" ${SBATCH_ARGS:-} "$out/render.sbatch")
array=${array%%;*}
# shellcheck disable=SC2086
merge=$($sbatch --parsable --dependency="afterok:$array" ${SBATCH_ARGS:-} "$out/merge.sbatch")
merge=${merge%%;*}
echo "submitted render array $array (N = $n, $split) and merge job $merge; result: $out/$stem.exr"
