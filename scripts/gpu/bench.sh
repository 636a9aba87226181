#!/bin/bash
# bench.sh --out DIR [--limit-s S] [--tiny]: the GPU benchmark (docs/gpu.md).
#
# Runs from the bundle folder (scripts/gpu/bundle.sh) alone: the papers'
# headline timing rows at the papers' resolutions, then a reduced
# compare_all, each part a study of bench/*.json. A part starts only if
# time is left before the limit, and runs under what is left; a part cut off
# by the limit (or that fails) leaves no result, only its log. DIR/README.md
# names the GPU, the driver, the date, the command and what finished.
#   --tiny   32 x 32 images, 1 frame, 16-spp references: a check in seconds
#   --parts a,b,...  only these parts (default: all, in the order below)
set -euo pipefail

here=$(cd "$(dirname "$(readlink -f "${BASH_SOURCE[0]}")")" && pwd)
die() {
    echo "bench.sh: $*" >&2
    exit 2
}
out="" limit=420 tiny=0 only=""
cmdline="bench.sh $*"
while (($#)); do
    case $1 in
    --out) out=${2:-} && shift 2 ;;
    --limit-s) limit=${2:-} && shift 2 ;;
    --tiny) tiny=1 && shift ;;
    --parts) only=${2:-} && shift 2 ;;
    -h | --help) sed -n '2,12s/^# \{0,1\}//p' "${BASH_SOURCE[0]}" && exit 0 ;;
    *) die "unknown argument '$1' (bench.sh --out DIR [--limit-s S] [--tiny] [--parts a,b])" ;;
    esac
done
[[ -n $out ]] || die "--out DIR is required"
[[ $limit =~ ^[0-9]+$ && $limit -gt 0 ]] || die "--limit-s needs a whole number of seconds > 0"
[[ ! -e $out || -z $(ls -A "$out" 2>/dev/null) ]] || die "$out exists and is not empty"
command -v timeout >/dev/null || die "needs timeout (coreutils) to keep to --limit-s"
gibench=$here/gibench
[[ -x $gibench && -d $here/scenes ]] ||
    die "runs from a bundle: scripts/gpu/bundle.sh DIR, then DIR/bench.sh (no $gibench here)"
parts=(gpu_paths cssm_table1 vlf_table1 avg_tables ivis_table1 csm_table2 timer_check compare)
if [[ -n $only ]]; then
    IFS=, read -r -a parts <<<"$only"
fi
for p in "${parts[@]}"; do
    [[ $p =~ ^[a-z0-9_]+$ && -f $here/bench/$p.json ]] || die "no part '$p' (bench/$p.json)"
done

mkdir -p "$out/logs"
out=$(cd "$out" && pwd)
work="$out/.work"
mkdir -p "$work"
deadline=$((SECONDS + limit))
started=$(date -u +%Y-%m-%dT%H:%M:%SZ)

# The device, as gibench sees it (the run records name it too).
if ! "$gibench" -v --version >"$out/device.txt" 2>"$out/logs/device.log"; then
    die "gibench cannot make a GL context: $(tail -1 "$out/logs/device.log")"
fi
if command -v nvidia-smi >/dev/null 2>&1; then
    nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader \
        >>"$out/device.txt" 2>/dev/null || true
fi
field() { sed -n "0,/^$1: /s/^$1: //p" "$out/device.txt"; }

# A part's study, made tiny for --tiny with sed alone (the node may have no
# python): 32 x 32, one frame, the cheapest settings, AVG's Table II at one
# size; the study files keep one method per line for this. The copy lies in
# the work folder, so its "base" becomes the bundle, where the scenes are.
prepare() {
    local src=$here/bench/$1.json dst=$work/$1.json
    if ((tiny)); then
        sed -E -e '/"size": \[(800|1024|1280|1920), *[0-9]+\], "frames"/d' \
            -e 's/"size": \[[0-9]+, *[0-9]+\]/"size": [32, 32]/g' \
            -e 's/"frames": [0-9]+/"frames": 1/g' -e 's/"spp": [0-9]+/"spp": 16/' \
            -e 's/"convergence_spp": \[[0-9, ]+\]/"convergence_spp": [4, 8]/' \
            -e 's/"atlas": [0-9]+, "M": [0-9]+/"atlas": 16, "M": 8/' \
            -e 's/"visibility": \[true, false\]/"visibility": true/' \
            -e 's/"N": \[8, 12, 16\]/"N": 8/' -e 's/"l": (128|512)/"l": 32/' \
            -e 's/"grid": 64, "vpls": 4096/"grid": 16, "vpls": 256/' \
            -e 's/"N": 128, "M": 128/"N": 8, "M": 32/' -e 's/"S": \[16, 64, 625\]/"S": [16]/' \
            -e "s|\"base\": \"[^\"]*\"|\"base\": \"$here\"|" "$src" >"$dst"
    else
        # the copy's scenes are the bundle's: its base is the bundle
        sed "s|\"base\": \"[^\"]*\"|\"base\": \"$here\"|" "$src" >"$dst"
    fi
}

declare -A status=() secs=()
interrupted=0
trap 'interrupted=1' INT TERM
for p in "${parts[@]}"; do
    left=$((deadline - SECONDS))
    if ((interrupted)); then
        status[$p]="skipped (bench.sh was interrupted)" && continue
    fi
    if ((left < 5)); then
        status[$p]="skipped (no time left of --limit-s $limit)" && continue
    fi
    prepare "$p"
    rm -rf "${work:?}/$p"
    t0=$SECONDS
    rc=0
    (cd "$here" && timeout --kill-after=10 "$left" "$gibench" -q study "$work/$p.json" \
        --out "$work/$p" --jobs 1) >"$out/logs/$p.log" 2>&1 || rc=$?
    secs[$p]=$((SECONDS - t0))
    if ((rc == 0)); then
        mv "$work/$p" "$out/$p"
        status[$p]="finished"
    elif ((rc == 1)) && [[ -f $work/$p/report.md && -f $work/$p/runs.csv ]]; then
        # the study ran to its end and wrote its report, but some runs failed
        # (e.g. a path this GL lacks): the other runs' timings are kept
        mv "$work/$p" "$out/$p"
        status[$p]="finished with failed runs: $(grep -c ',failed,' "$out/$p/runs.csv" || true) (see $p/report.md, logs/$p.log)"
    else
        rm -rf "${work:?}/$p"
        if ((rc == 124 || rc == 137)); then
            status[$p]="cut off at the time limit after ${secs[$p]} s (no result kept)"
        else
            status[$p]="failed (exit $rc, see logs/$p.log; no result kept)"
        fi
    fi
done
rm -rf "$work"

tmp_readme="$out/.README.md.tmp"
{
    echo "# gibench GPU benchmark"
    echo
    echo "- GPU: $(field 'GL renderer')"
    echo "- GL version (driver): $(field 'GL version'), vendor $(field 'GL vendor')"
    echo "- EGL device: $(field 'EGL device')"
    if [[ $(wc -l <"$out/device.txt") -gt 7 ]]; then
        echo "- nvidia-smi: $(tail -1 "$out/device.txt")"
    fi
    echo "- CPU cores (path tracer): $(nproc 2>/dev/null || echo '?')"
    echo "- date: $started (UTC); $(sed -n 1p "$out/device.txt")"
    echo "- command: \`$cmdline\`$( ((tiny)) && echo ' (tiny mode: 32 x 32, not timings to publish)')"
    echo
    echo "| part | study | status | seconds |"
    echo "| --- | --- | --- | --- |"
    for p in "${parts[@]}"; do
        echo "| $p | bench/$p.json | ${status[$p]} | ${secs[$p]:--} |"
    done
    echo
    echo "Each finished part's folder holds the study's runs.csv and report.md; the"
    echo "timer used for the GPU stages is the \"timer\" column (gl-timestamp-query on"
    echo "a GPU). Compare with the papers and llvmpipe: scripts/gpu/gpu_table.py."
} >"$tmp_readme"
mv "$tmp_readme" "$out/README.md"
cat "$out/README.md"
((interrupted == 0)) || exit 130
