"""20 renders of a 64x64 image in one Python process against 20 `gibench render`
processes (docs/python.md "Cost of a render"): prints both wall times and their ratio.

    PYTHONPATH=build/release/python /usr/bin/python3 examples/python/timing.py [METHOD] [N] [fresh] [no-cache]

Run from the repository root on an otherwise idle machine. Both sides render the
same images (the in-process ones are checked against the last CLI one); the
Python side counts from before `import gibench`, so the one-time cost of the GL
context, the plugins and the scene load is in it. The renders differ in their
seed only, so the scene's kept instance serves all but the first (one prepare);
`fresh` makes every render create and prepare its own, as each CLI process does;
`no-cache` precomputes afresh on both sides (render --no-cache, no_cache=True).
"""
import os
import subprocess
import sys
import tempfile
import time

METHOD = sys.argv[1] if len(sys.argv) > 1 else "direct"
N = int(sys.argv[2]) if len(sys.argv) > 2 else 20
FRESH = "fresh" in sys.argv[3:]
NO_CACHE = "no-cache" in sys.argv[3:]
SCENE = "scenes/cornell_box.gltf"

t0 = time.perf_counter()
import gibench  # noqa: E402  (timed: the import is part of the in-process cost)

scene = gibench.Scene(SCENE)
images = [scene.render(METHOD, size=(64, 64), seed=k + 1, fresh=FRESH, no_cache=NO_CACHE)
          for k in range(N)]
t_py = time.perf_counter() - t0

from gibench import _build  # noqa: E402

with tempfile.TemporaryDirectory() as tmp:
    t0 = time.perf_counter()
    for k in range(N):
        out = os.path.join(tmp, "%d.exr" % k)
        subprocess.run([_build.COMMAND, "-q", "render", "--scene", SCENE, "--method", METHOD,
                        "--size", "64x64", "--seed", str(k + 1), "--out", out]
                       + (["--no-cache"] if NO_CACHE else []), check=True)
    t_cli = time.perf_counter() - t0
    last = gibench.read(os.path.join(tmp, "%d.exr" % (N - 1)))

import numpy as np  # noqa: E402

assert np.array_equal(last, images[-1]), "the in-process image differs from the CLI's"
print("%d renders of %s, 64x64%s: one Python process%s %.2f s, %d gibench processes %.2f s, "
      "ratio %.2f" % (N, METHOD, ", no cache" if NO_CACHE else "", " (fresh)" if FRESH else "",
                      t_py, N, t_cli, t_py / t_cli))
