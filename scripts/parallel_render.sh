#!/usr/bin/env bash
# Render SCENE with GNU parallel, as N tiles (or sample ranges) over local cores
# or ssh hosts, then merge the parts.
#
#   scripts/parallel_render.sh SCENE N [--split tiles|samples] [--out DIR]
#                              [--hosts LIST] [--jobs J] [-- RENDER ARGS...]
#
#   --split tiles    part K renders `--tile K/N` (default)
#   --split samples  part K renders samples ⌊K·S/N⌋..⌊(K+1)·S/N⌋ of S = --spp
#   --out DIR        parts and the merged DIR/<scene>.exr + .png
#                    [default: out/<scene>-parallel]
#   --hosts LIST     GNU parallel's --sshlogin list (e.g. "8/node1,8/node2");
#                    the binary, scene and DIR must be at the same paths there
#                    (a shared file system). Default: this machine only.
#   --jobs J         parts at once per host [default: the cores]; each part
#                    renders with --threads 1 when J > 1, so cores are not
#                    oversubscribed.
#
# Environment: GRADTRACE (the binary, default: the one built in this checkout).
set -euo pipefail

usage() { sed -n '2,20p' "$0" | sed 's/^# \{0,1\}//'; exit 2; }
[ $# -ge 2 ] || usage
scene=$1 n=$2
shift 2
split=tiles out="" hosts="" jobs=""
while [ $# -gt 0 ]; do
    case $1 in
        --split) split=${2:?--split needs tiles or samples}; shift 2 ;;
        --out) out=${2:?--out needs a directory}; shift 2 ;;
        --hosts) hosts=${2:?--hosts needs a list}; shift 2 ;;
        --jobs) jobs=${2:?--jobs needs a number}; shift 2 ;;
        --) shift; break ;;
        *) echo "parallel_render.sh: unknown option $1 (render args go after --)" >&2; exit 2 ;;
    esac
done
case $n in ''|*[!0-9]*|0) echo "parallel_render.sh: N must be a positive integer, got '$n'" >&2; exit 2 ;; esac
[ -f "$scene" ] || { echo "parallel_render.sh: $scene: no such scene file" >&2; exit 2; }
command -v parallel >/dev/null || { echo "parallel_render.sh: GNU parallel is not installed (Debian: apt-get install parallel)" >&2; exit 2; }

here=$(cd "$(dirname "$0")/.." && pwd)
gradtrace=${GRADTRACE:-$here/target/release/gradtrace}
stem=$(basename "${scene%.*}")
out=${out:-out/$stem-parallel}
mkdir -p "$out"
scene=$(cd "$(dirname "$scene")" && pwd)/$(basename "$scene")
out=$(cd "$out" && pwd)
jobs=${jobs:-$(nproc)}

case $split in
    tiles) part_arg() { echo "--tile $1/$n"; } ;;
    samples)
        spp="" prev=""
        for a in "$@"; do
            [ "$prev" = "--spp" ] && spp=$a
            case $a in --spp=*) spp=${a#--spp=} ;; esac
            prev=$a
        done
        [ -n "$spp" ] || { echo "parallel_render.sh: --split samples needs --spp S among the render args" >&2; exit 2; }
        [ "$spp" -ge "$n" ] || { echo "parallel_render.sh: --spp $spp is less than N = $n sample ranges" >&2; exit 2; }
        part_arg() { echo "--spp-range $(($1 * spp / n)):$((($1 + 1) * spp / n))"; } ;;
    *) echo "parallel_render.sh: --split must be tiles or samples, got '$split'" >&2; exit 2 ;;
esac

threads=()
[ "$jobs" -gt 1 ] && threads=(--threads 1)
render_args=""
for a in "${threads[@]}" "$@"; do render_args+=" $(printf '%q' "$a")"; done

# One line per part: the full command, so that parallel runs the same thing on
# any host (and --dry-run shows it).
for ((k = 0; k < n; k++)); do
    echo "$(printf '%q' "$gradtrace") render $(printf '%q' "$scene") $(part_arg "$k") --quiet --out $(printf '%q' "$out/part-$k.exr")$render_args"
done > "$out/commands.txt"

ssh=()
[ -n "$hosts" ] && ssh=(--sshlogin "$hosts")
parallel --halt now,fail=1 --jobs "$jobs" "${ssh[@]}" --joblog "$out/joblog.txt" < "$out/commands.txt"

parts=()
for ((k = 0; k < n; k++)); do parts+=("$out/part-$k.exr"); done
"$gradtrace" merge "${parts[@]}" --out "$out/$stem.exr"
