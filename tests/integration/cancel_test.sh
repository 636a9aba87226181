#!/usr/bin/env bash
# Every method stops soon after Ctrl-C while it precomputes on a large scene
# (issue 32, item 7: vlf used to go on for minutes on 2 M triangles): a
# scene of about 250 k triangles (big_scene.py; CANCEL_GRID=700: 1 M), one render per method with
# -v; SIGINT two seconds (CANCEL_AFTER) after "prepare begins"; the CPU time the
# process spends from the signal to its exit must be under LIMIT seconds
# (CANCEL_LIMIT, 2 by default; CPU time, not wall time, which on a shared
# machine measures the neighbours). A method that finishes first passes.
# usage: cancel_test.sh GIBENCH ROOT OUT [METHOD...]
set -u
GIB=$1 ROOT=$2 OUT=$3
shift 3
LIMIT=${CANCEL_LIMIT:-2}
fail() { echo "FAIL: $*" >&2; exit 1; }
D=$OUT/cancel
rm -rf "$D" && mkdir -p "$D" || fail "cannot create $D"
/usr/bin/python3 "$ROOT/tests/integration/big_scene.py" "$ROOT" "$D/big.gltf" "${CANCEL_GRID:-350}" || fail "could not make the scene"
methods=("$@")
[ ${#methods[@]} -gt 0 ] || methods=(direct csm cssm_hrc implicit_vis vlf avg)
failed=0
for m in "${methods[@]}"; do
    log=$D/$m.log
    GIBENCH_CACHE=$D/cache "$GIB" -v render --scene "$D/big.gltf" --method "$m" --size 32x32 \
        --out "$D/$m.exr" --no-cache 2>"$log" >/dev/null &
    pid=$!
    for _ in $(seq 1200); do
        grep -q "prepare begins" "$log" 2>/dev/null && break
        kill -0 $pid 2>/dev/null || break
        sleep 0.05
    done
    if ! grep -q "prepare begins" "$log"; then
        kill -9 $pid 2>/dev/null; wait $pid 2>/dev/null
        echo "$m: never began to prepare: $(tail -n 2 "$log")"; failed=1; continue
    fi
    sleep "${CANCEL_AFTER:-2}"
    # CPU time (user + system, all threads) the process spends after the
    # signal, read from /proc until it is gone: on a shared, loaded machine
    # the wall time says more about the neighbours than about the method
    cpu() { awk '{ print $14 + $15 }' "/proc/$pid/stat" 2>/dev/null; }
    c0=$(cpu)
    t0=$(date +%s.%N)
    kill -INT $pid 2>/dev/null
    c1=$c0
    # wait, but not for ever: SIGKILL once it has spent 5 x LIMIT of CPU
    # after the signal (it has failed then), or after 300 s of wall time
    hz=$(getconf CLK_TCK)
    deadline=$(($(date +%s) + 300))
    while kill -0 $pid 2>/dev/null && [ "$(date +%s)" -lt $deadline ]; do
        c=$(cpu)
        [ -n "$c" ] && c1=$c
        awk -v a="${c0:-0}" -v b="$c1" -v hz="$hz" -v l="$LIMIT" 'BEGIN { exit !((b - a) / hz > 5 * l) }' && break
        sleep 0.1
    done
    kill -9 $pid 2>/dev/null
    wait $pid
    rc=$?
    t1=$(date +%s.%N)
    wall=$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.2f", b - a }')
    took=$(awk -v a="${c0:-0}" -v b="${c1:-0}" -v hz="$hz" 'BEGIN { printf "%.2f", (b - a) / hz }')
    verdict=ok
    if awk -v t="$took" -v l="$LIMIT" 'BEGIN { exit !(t > l) }'; then verdict="too slow"; failed=1; fi
    if [ $rc = 137 ]; then verdict="$verdict, still running (killed)"; failed=1; fi
    echo "$m: ${took} s of CPU (${wall} s wall) from SIGINT to exit (exit $rc): $verdict; $(tail -n 1 "$log")"
done
[ $failed = 0 ] || fail "some methods did not stop within $LIMIT s of SIGINT"
echo "every method stopped within $LIMIT s of SIGINT"
