#!/usr/bin/env bash
# Fault injection (issue 32): each fault costs one cell, never a study, and
# nothing stale or half-written is kept.
#   broken plugin   a plugin whose destructor crashes sits in the plugin
#                   path: `methods --json` is whole, the study's `direct`
#                   run is ok (every run used to crash at exit);
#   kill -9         a run's render is killed with SIGKILL (as the OOM
#                   killer does): that run alone is not ok, the other run
#                   is ok, the study finishes;
#   full disk       the study's folder on a full tmpfs (root only, else
#                   skipped): the study fails with "No space left on
#                   device", leaves no temporary file, and once space is
#                   freed the same command completes;
#   interrupted reference
#                   the scene is edited, the study interrupted (SIGTERM)
#                   while it re-renders the reference, then resumed: the
#                   reference it uses is the new scene's (bit-identical to
#                   a fresh study's), never the old one.
# usage: faults.sh GIBENCH ROOT OUT FAKE_RUN_DIR FAKE_PLUGIN_DIR
set -u
GIB=$1 ROOT=$2 OUT=$3 FAKE_RUN=$4 FAKE_PLUGINS=$5
D=$OUT/faults
failed=0
fail() { echo "FAIL: $*" >&2; failed=1; }
rm -rf "$D" && mkdir -p "$D" || { echo "FAIL: cannot create $D"; exit 1; }
cd "$ROOT" || exit 1
unset GIBENCH_PLUGIN_PATH
export GIBENCH_CACHE=$D/cache

# status RUNS_CSV METHOD_OR_LABEL: the status column of that run
status() {
    /usr/bin/python3 -c 'import csv, sys
rows = [r for r in csv.DictReader(open(sys.argv[1])) if sys.argv[2] in (r["method"], r["label"])]
print(" ".join(r["status"] + ("(" + r["reason"] + ")" if r["reason"] else "") for r in rows))' "$1" "$2" 2>/dev/null
}

study_file() { # NAME SCENE SPP METHODS_JSON [extra json]
    cat > "$D/$1.json" <<JSON
{"name": "$1", "base": "$ROOT", "scenes": ["$2"], "size": [16, 16], "frames": 1, "warmup": 0, "timeout": 60,
 "methods": $4, "reference": {"spp": $3, "max_bounces": 2}${5:-}}
JSON
}

# --- broken plugin ---
mkdir -p "$D/plugins" && cp "$FAKE_PLUGINS/gimethod_fake_dtor_crash.so" "$D/plugins/"
export GIBENCH_PLUGIN_PATH=$D/plugins
"$GIB" -q methods --json >"$D/methods.json" 2>"$D/methods.err"
rc=$?
[ $rc = 0 ] || fail "broken plugin: methods --json exited $rc"
/usr/bin/python3 -c 'import json, sys; json.load(open(sys.argv[1]))' "$D/methods.json" 2>/dev/null ||
    fail "broken plugin: methods --json is not whole JSON"
study_file broken scenes/cornell_box_coarse.gltf 4 '[{"method": "direct"}]' ', "compare": false'
"$GIB" study "$D/broken.json" --out "$D/broken" >"$D/broken.log" 2>&1
st=$(status "$D/broken/runs.csv" direct)
[ "$st" = ok ] || fail "broken plugin: the direct run is '$st' (expected ok): $(tail -n 3 "$D/broken.log")"
echo "broken plugin: methods --json whole (rc $rc), direct run: $st"
unset GIBENCH_PLUGIN_PATH

# --- kill -9 of a child ---
export GIBENCH_PLUGIN_PATH=$FAKE_RUN
study_file kill scenes/cornell_box_coarse.gltf 4 '[{"method": "fake_hang"}, {"method": "direct"}]' ', "compare": false'
"$GIB" study "$D/kill.json" --out "$D/kill" >"$D/kill.log" 2>&1 &
sp=$!
victim=
for _ in $(seq 600); do
    victim=$(ps -eo pid=,args= | awk -v d="$D/kill/runs/" 'index($0, d) && /render/ && /fake_hang/ && !/awk/ { print $1; exit }')
    [ -n "$victim" ] && break
    kill -0 $sp 2>/dev/null || break
    sleep 0.1
done
if [ -z "$victim" ]; then
    fail "kill -9: the fake_hang run's render never started"
    kill $sp 2>/dev/null
else
    sleep 0.5
    kill -9 "$victim"
fi
for _ in $(seq 1200); do kill -0 $sp 2>/dev/null || break; sleep 0.1; done
if kill -0 $sp 2>/dev/null; then
    fail "kill -9: the study did not finish within 120 s of the kill"
    kill $sp
fi
wait $sp
rc=$?
[ $rc -lt 128 ] || fail "kill -9: the study itself died (exit $rc)"
st_hang=$(status "$D/kill/runs.csv" fake_hang) st_direct=$(status "$D/kill/runs.csv" direct)
case "$st_hang" in ok* | "") fail "kill -9: the killed run is '$st_hang' (expected not ok)" ;; esac
[ "$st_direct" = ok ] || fail "kill -9: the other run is '$st_direct' (expected ok)"
echo "kill -9: study exit $rc; killed run: $st_hang; other run: $st_direct"
unset GIBENCH_PLUGIN_PATH

# --- full disk ---
M=$D/full
mkdir -p "$M"
if [ "$(id -u)" != 0 ] || ! mount -t tmpfs -o size=1m tmpfs "$M" 2>/dev/null; then
    echo "full disk: SKIPPED (no tmpfs can be mounted: not root)"
else
    dd if=/dev/zero of="$M/filler" bs=4k 2>/dev/null
    study_file full scenes/cornell_box_coarse.gltf 4 '[{"method": "direct"}]'
    "$GIB" study "$D/full.json" --out "$M/s" >"$D/full.log" 2>&1
    rc=$?
    { [ $rc != 0 ] && [ $rc -lt 128 ]; } || fail "full disk: the study exited $rc (expected a failure, not a crash)"
    grep -q "No space left on device" "$D/full.log" || fail "full disk: no 'No space left on device' line: $(tail -n 3 "$D/full.log")"
    left=$(find "$M" -name '*.tmp-*' 2>/dev/null)
    [ -z "$left" ] || fail "full disk: temporary files left: $left"
    rm -f "$M/filler"
    "$GIB" study "$D/full.json" --out "$M/s" >"$D/full2.log" 2>&1
    rc2=$?
    st=$(status "$M/s/runs.csv" direct)
    [ $rc2 = 0 ] && [ "$st" = ok ] || fail "full disk: after freeing space the study exited $rc2, run '$st': $(tail -n 3 "$D/full2.log")"
    echo "full disk: study exit $rc ($(grep -m1 "No space" "$D/full.log")); after freeing space: exit $rc2, run $st"
    umount "$M"
fi

# --- interrupted reference ---
mkdir -p "$D/scene"
cp scenes/cornell_box_coarse.gltf scenes/cornell_box_coarse.bin "$D/scene/"
study_file iref "$D/scene/cornell_box_coarse.gltf" 2048 '[{"method": "direct"}]'
"$GIB" study "$D/iref.json" --out "$D/iref" >"$D/iref1.log" 2>&1 || fail "interrupted reference: the first study failed"
# the red wall turns blue: a different scene, the same settings
/usr/bin/python3 - "$D/scene/cornell_box_coarse.gltf" <<'PY'
import json, sys
g = json.load(open(sys.argv[1]))
for m in g["materials"]:
    if m["name"] == "red":
        m["pbrMetallicRoughness"]["baseColorFactor"] = [0.05, 0.065, 0.63, 1.0]
json.dump(g, open(sys.argv[1], "w"))
PY
"$GIB" study "$D/iref.json" --out "$D/iref" >"$D/iref2.log" 2>&1 &
sp=$!
seen=
for _ in $(seq 600); do
    ps -eo args= | grep -F "$D/iref/references" | grep -v grep | grep -q reference && { seen=1; break; }
    kill -0 $sp 2>/dev/null || break
    sleep 0.05
done
[ -n "$seen" ] || fail "interrupted reference: the study never re-rendered the reference (did it see the edit?)"
sleep 0.3
kill -TERM $sp 2>/dev/null
wait $sp
"$GIB" study "$D/iref.json" --out "$D/iref" >"$D/iref3.log" 2>&1 || fail "interrupted reference: resuming failed: $(tail -n 3 "$D/iref3.log")"
"$GIB" study "$D/iref.json" --out "$D/iref_fresh" >"$D/iref4.log" 2>&1 || fail "interrupted reference: the fresh study failed"
for ref in "$D"/iref_fresh/references/*.exr; do
    b=$(basename "$ref")
    r=$("$GIB" diff "$D/iref/references/$b" "$ref" 2>&1 | awk '$1 == "relmse" { print $2 }')
    [ "$r" = 0 ] || fail "interrupted reference: $b after resuming differs from the new scene's (relmse ${r:-?}): the stale reference was kept"
    echo "interrupted reference: $b vs a fresh study's: relmse ${r:-?}"
done

[ $failed = 0 ] || { echo "FAIL: some faults cost more than their cell"; exit 1; }
echo "faults: every fault cost its cell alone"
