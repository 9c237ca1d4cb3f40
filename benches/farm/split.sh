#!/usr/bin/env bash
# Benchmark (not in CI) of split renders on this machine: the wall time of a render split
# 1, 2 and 4 ways through a real single-node Slurm (tests/slurm/cluster.sh; root, Debian's
# slurmctld slurmd slurm-client munge) against one process, and the cost of `kiln merge`
# per megapixel. Prints Markdown tables for docs/BENCHMARKS.md.
#
#   cargo build --release && benches/farm/split.sh [SIZE] [SPP]     # default 256x256 256
set -euo pipefail
cd "$(dirname "$0")/../.."
root=$PWD
kiln=$root/target/release/kiln
size=${1:-256x256}
spp=${2:-256}
work=$(mktemp -d)
trap 'bash "$root/tests/slurm/cluster.sh" stop "$work/cluster" >/dev/null 2>&1 || true; rm -rf "$work"' EXIT
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-$(mktemp -d)}
mkdir -p "$work/cluster"
eval "$(bash tests/slurm/cluster.sh start "$work/cluster" 2>/dev/null)"
cd "$work"
now() { date +%s.%N; }
since() { echo "$(now) - $1" | bc -l | xargs printf '%.2f'; }

# Warm Mesa's shader cache: every process after this one finds the kernel compiled.
"$kiln" render --size 16x16 --spp 1 -q -o warm.png 2>/dev/null

echo "adapter: $("$kiln" info 2>/dev/null | grep -m1 -i 'would use\|using' || true)"
echo
echo "| run ($size, $spp spp, Cornell box) | wall time (s) |"
echo "|---|---:|"
# PNG outputs throughout: an EXR output would make the one-process render also
# accumulate the AOV layers, which parts do not.
t=$(now)
"$kiln" render --size "$size" --spp "$spp" -q -o one.png 2>/dev/null
echo "| one process, \`kiln render\` | $(since "$t") |"
for parts in 1 2 4; do
    t=$(now)
    "$kiln" farm slurm --parts "$parts" --spp "$spp" -o "farm$parts.png" --submit -- --size "$size" 2>/dev/null
    until [ -z "$(squeue -h)" ]; do sleep 0.1; done
    cmp -s "farm$parts.png" one.png || { echo "farm$parts.png differs from one.png" >&2; exit 1; }
    echo "| Slurm, $parts part(s) + merge job | $(since "$t") |"
done

# The merge alone: 4 parts of a 1920x1080 frame at 1 spp each.
for p in 0 1 2 3; do
    "$kiln" render --size 1920x1080 --spp 4 --samples "$p..$((p + 1))" -q -o "big$p.exr" 2>/dev/null
done
echo
echo "| merge of 4 parts of 1920×1080 (2.07 MP) | time (s) | per megapixel (s) |"
echo "|---|---:|---:|"
for out in merged.exr merged.png; do
    t=$(now)
    "$kiln" merge big0.exr big1.exr big2.exr big3.exr -o "$out" 2>/dev/null
    s=$(since "$t")
    echo "| to $out | $s | $(echo "$s / 2.0736" | bc -l | xargs printf '%.2f') |"
done
echo
echo "part file size at 1920×1080: $(du -k big0.exr | cut -f1) KiB"
