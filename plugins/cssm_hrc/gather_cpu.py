#!/usr/bin/env python3
"""CPU time of cssm_hrc's frames with gather=gpu and gather=cpu (issue 29;
README "Where each stage runs").

gather_cpu.py GIBENCH SCENE [SIZE [ROUNDS]]

Per gather, alternating, ROUNDS times (default 2): `gibench -q render` of
SCENE at SIZE (default 128x128) with 1 and with 7 frames (1 warm-up each,
the maps from the cache), the CPU time of every thread of the process
sampled from /proc every 10 ms. The difference of the two runs is the cost
of 6 frames: per frame the wall time, the CPU time of all threads, of the
main thread, and the main thread's share of it. Linux only."""
import os
import subprocess
import sys
import time

TICK = os.sysconf("SC_CLK_TCK")


def thread_times(pid):
    """{tid: (cpu seconds, name)} of every thread of pid now."""
    out = {}
    try:
        tids = os.listdir("/proc/%d/task" % pid)
    except OSError:
        return out
    for tid in tids:
        try:
            with open("/proc/%d/task/%s/stat" % (pid, tid)) as f:
                s = f.read()
        except OSError:
            continue
        name = s[s.index("(") + 1:s.rindex(")")]
        fields = s[s.rindex(")") + 2:].split()
        out[int(tid)] = ((int(fields[11]) + int(fields[12])) / TICK, name)
    return out


def run(gib, scene, size, gather, frames):
    """(wall s, all threads' CPU s, main thread's CPU s) of one render."""
    img = os.path.join(os.environ.get("TMPDIR", "/tmp"), "gather_cpu_%d.pfm" % os.getpid())
    cmd = [gib, "-q", "render", "--scene", scene, "--method", "cssm_hrc", "--size", size, "--frames",
           str(frames), "--warmup", "1", "--param", "gather=" + gather, "--out", img]
    t0 = time.monotonic()
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    seen = {}
    while p.poll() is None:
        seen.update(thread_times(p.pid))
        time.sleep(0.01)
    wall = time.monotonic() - t0
    if p.returncode != 0:
        sys.exit("FAIL: %s: %s" % (" ".join(cmd), p.stderr.read().decode().strip()[-300:]))
    return wall, sum(t for t, _ in seen.values()), seen.get(p.pid, (0.0, ""))[0]


def main(gib, scene, size="128x128", rounds="2"):
    res = {"gpu": [], "cpu": []}
    for _ in range(int(rounds)):
        for g in ("gpu", "cpu"):
            a, b = run(gib, scene, size, g, 1), run(gib, scene, size, g, 7)
            res[g].append([(y - x) / 6.0 for x, y in zip(a, b)])
    print("gather | wall ms/frame | CPU ms/frame (all threads) | main thread ms/frame | main share")
    for g, rows in res.items():
        for wall, cpu, main_t in rows:
            print("%s | %.0f | %.0f | %.0f | %.2f" % (g, 1e3 * wall, 1e3 * cpu, 1e3 * main_t,
                                                     main_t / cpu if cpu > 0 else float("nan")))


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit("usage: gather_cpu.py GIBENCH SCENE [SIZE [ROUNDS]]")
    main(*sys.argv[1:])
