#!/usr/bin/env python3
"""Start-up time of gibench builds, measured in paired, interleaved runs.

    scripts/startup_time.py [--runs N] NAME=PATH/TO/gibench [NAME=...]

Every round runs, in a fresh random order, `/bin/true` (a process that does
nothing), and for each build `gibench methods` and a 16x16 one-frame render
of the Cornell box with the `direct` method writing an EXR and a PNG (what
a study cell writes), once with Mesa's shader cache as the earlier runs
left it (warm) and once with it disabled (MESA_SHADER_CACHE_DISABLE=true:
every shader compiled, as on a machine's first run). Wall time per run and CPU time (user + system of the
child, from getrusage) are kept; the report (Markdown, on standard output:
`make results` keeps it as results/startup.md) gives medians and the
overhead over /bin/true, and the ratio of each build to the first one. CPU time is
less sensitive than wall time to other processes sharing the machine.
Run from the repository root (the scene path is relative to it).
"""
import os
import random
import resource
import statistics
import subprocess
import sys
import tempfile
import time


def run(argv, env=None):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    p = subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                       env=None if env is None else dict(os.environ, **env))
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode != 0:
        sys.exit("startup_time: %s failed (%d): %s" % (" ".join(argv), p.returncode,
                                                      p.stderr.decode(errors="replace").strip()))
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def main():
    args = sys.argv[1:]
    runs = 30
    if len(args) >= 2 and args[0] == "--runs":
        runs = int(args[1])
        args = args[2:]
    builds = []
    for a in args:
        name, _, path = a.partition("=")
        if not path or not os.access(path, os.X_OK):
            sys.exit("startup_time: '%s' is not NAME=EXECUTABLE" % a)
        builds.append((name, path))
    if not builds:
        sys.exit(__doc__)
    tmp = tempfile.mkdtemp(prefix="gibench-startup-")
    cmds = [("true", "-", ["/bin/true"], None)]
    cold = {"MESA_SHADER_CACHE_DISABLE": "true"}
    for name, path in builds:
        cmds.append(("methods", name, [path, "methods"], None))
        render = [path, "render", "--scene", "scenes/cornell_box.gltf", "--method", "direct",
                  "--size", "16x16", "--frames", "1", "--warmup", "0",
                  "--out", os.path.join(tmp, name + ".exr"), "--out", os.path.join(tmp, name + ".png")]
        cmds.append(("render 16x16, warm shader cache", name, render, None))
        cmds.append(("render 16x16, cold shader cache", name, render, cold))
    for c in cmds:  # one untimed run each: page cache, shader cache
        run(c[2], c[3])
    wall = {i: [] for i in range(len(cmds))}
    cpu = {i: [] for i in range(len(cmds))}
    rng = random.Random(1)
    for _ in range(runs):
        order = list(range(len(cmds)))
        rng.shuffle(order)
        for i in order:
            w, c = run(cmds[i][2], cmds[i][3])
            wall[i].append(w)
            cpu[i].append(c)
    med_w = {i: statistics.median(v) for i, v in wall.items()}
    med_c = {i: statistics.median(v) for i, v in cpu.items()}
    load = os.getloadavg()
    print("# Start-up time\n")
    print("Made by `scripts/startup_time.py --runs %d %s`: %d interleaved rounds in a random order, "
          "medians; CPU time = user + system of the child; overhead = the command's median "
          "minus `/bin/true`'s. Load average at the end: %.1f, %.1f, %.1f (1, 5, 15 min); %d cores.\n"
          % (runs, " ".join("%s=%s" % b for b in builds), runs, load[0], load[1], load[2],
             os.cpu_count() or 0))
    print("| command | build | wall (s) | CPU (s) | wall overhead (s) | CPU overhead (s) |")
    print("|---|---|---:|---:|---:|---:|")
    for i, (what, name, _, _) in enumerate(cmds):
        print("| %s | %s | %.4f | %.4f | %.4f | %.4f |" % (what, name, med_w[i], med_c[i],
                                                        med_w[i] - med_w[0], med_c[i] - med_c[0]))
    if len(builds) > 1:
        print("\nRatios of paired medians (each round's run of the first build / the same round's "
              "run of the other):\n")
        print("| command | builds | wall | CPU |")
        print("|---|---|---:|---:|")
        for what in sorted({c[0] for c in cmds if c[1] != "-"}):
            first = [i for i, c in enumerate(cmds) if c[0] == what][0]
            for i, c in enumerate(cmds):
                if c[0] == what and i != first:
                    rw = statistics.median(a / b for a, b in zip(wall[first], wall[i]))
                    rc = statistics.median(a / b for a, b in zip(cpu[first], cpu[i]) if b > 0)
                    print("| %s | %s / %s | %.2f× | %.2f× |" % (what, cmds[first][1], c[1], rw, rc))

if __name__ == "__main__":
    main()
