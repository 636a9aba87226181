#!/usr/bin/env bash
# Every method stops soon after SIGINT or SIGTERM (issue 32, item 7: vlf
# used to go on for minutes on 2 M triangles, avg and implicit_vis for a
# minute or two on 250 k). On a scene of 2 * CANCEL_GRID^2 triangles
# (big_scene.py; 120: about 29 k, just enough that the old avg and
# implicit_vis take more than 2 s to stop), each method renders many
# frames with -v and gets the signal CANCEL_AFTER seconds after "prepare
# begins" (in prepare() for the slow ones, in a frame or between frames for
# the fast ones); a method's runs for the two signals go side by side. It must then exit within LIMIT seconds (CANCEL_LIMIT, 2;
# CPU time of all its threads, not wall time, which on a shared machine
# measures the neighbours), with a non-zero status other than a kill, a
# last line that says it was cancelled or interrupted, and no image.
# usage: cancel_test.sh GIBENCH ROOT OUT [METHOD...]
#   CANCEL_SIGNALS: the signals, each method is run once per signal (INT TERM)
set -u
GIB=$1 ROOT=$2 OUT=$3
shift 3
LIMIT=${CANCEL_LIMIT:-2}
fail() { echo "FAIL: $*" >&2; exit 1; }
D=$OUT/cancel
rm -rf "$D" && mkdir -p "$D" || fail "cannot create $D"
/usr/bin/python3 "$ROOT/tests/integration/big_scene.py" "$ROOT" "$D/big.gltf" "${CANCEL_GRID:-120}" || fail "could not make the scene"
methods=("$@")
[ ${#methods[@]} -gt 0 ] || methods=(direct csm cssm_hrc implicit_vis vlf avg)
hz=$(getconf CLK_TCK)
failed=0

# one run of method $1 stopped by signal $2; prints a line, ending in
# " FAILED" when it fails
run_one() {
    local m=$1 sig=$2 log=$D/$1.$2.log img=$D/$1.$2.exr
    GIBENCH_CACHE=$D/cache "$GIB" -v render --scene "$D/big.gltf" --method "$m" --size 32x32 \
        --frames 100000 --out "$img" --no-cache 2>"$log" >/dev/null &
    local pid=$!
    local until=$(($(date +%s) + 30))
    while [ "$(date +%s)" -lt $until ]; do
        grep -q "prepare begins" "$log" 2>/dev/null && break
        kill -0 $pid 2>/dev/null || break
        sleep 0.05
    done
    if ! grep -q "prepare begins" "$log"; then
        kill -9 $pid 2>/dev/null
        wait $pid 2>/dev/null
        echo "$m (SIG$sig): never began to prepare: $(tail -n 2 "$log") FAILED"
        return
    fi
    sleep "${CANCEL_AFTER:-1}"
    # CPU time (user + system, all threads) the process spends after the
    # signal, read from /proc until it is gone
    cpu() { awk '{ print $14 + $15 }' "/proc/$pid/stat" 2>/dev/null; }
    local c0 c1 c t0 t1 rc
    c0=$(cpu)
    t0=$(date +%s.%N)
    kill -"$sig" $pid 2>/dev/null
    c1=$c0
    # wait, but not for ever: SIGKILL once it has spent 3 x LIMIT of CPU
    # after the signal (it has failed then), or after 60 s of wall time
    local deadline=$(($(date +%s) + 60))
    while kill -0 $pid 2>/dev/null && [ "$(date +%s)" -lt $deadline ]; do
        c=$(cpu)
        [ -n "$c" ] && c1=$c
        awk -v a="${c0:-0}" -v b="$c1" -v hz="$hz" -v l="$LIMIT" 'BEGIN { exit !((b - a) / hz > 3 * l) }' && break
        sleep 0.05
    done
    kill -9 $pid 2>/dev/null
    wait $pid
    rc=$?
    t1=$(date +%s.%N)
    local wall took last verdict=ok failed=0
    wall=$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.2f", b - a }')
    took=$(awk -v a="${c0:-0}" -v b="${c1:-0}" -v hz="$hz" 'BEGIN { printf "%.2f", (b - a) / hz }')
    last=$(tail -n 1 "$log")
    if awk -v t="$took" -v l="$LIMIT" 'BEGIN { exit !(t > l) }'; then verdict="too slow"; failed=1; fi
    if [ $rc = 137 ]; then
        verdict="$verdict, still running (killed)"; failed=1
    elif [ $rc = 0 ]; then
        verdict="$verdict, exit 0 after the signal"; failed=1
    elif ! [[ $last =~ ^gibench:\ .*(cancelled|interrupted) ]]; then
        verdict="$verdict, last line does not say cancelled or interrupted"; failed=1
    fi
    if [ -e "$img" ]; then verdict="$verdict, wrote an image"; failed=1; fi
    echo "$m (SIG$sig): ${took} s of CPU (${wall} s wall) from the signal to exit (exit $rc): $verdict; $last$([ $failed = 0 ] || echo " FAILED")"
}

# the signals' runs of a method side by side (the CPU time each spends
# does not depend on its neighbour), the methods one after the other
for m in "${methods[@]}"; do
    for sig in ${CANCEL_SIGNALS:-INT TERM}; do
        run_one "$m" "$sig" >"$D/$m.$sig.result" &
    done
    wait
    for sig in ${CANCEL_SIGNALS:-INT TERM}; do
        cat "$D/$m.$sig.result"
        grep -q ' FAILED$' "$D/$m.$sig.result" && failed=1
    done
done
[ $failed = 0 ] || fail "some methods did not stop cleanly within $LIMIT s of the signal"
echo "every method stopped within $LIMIT s of the signal"
