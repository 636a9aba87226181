# %% [markdown]
# # gibench from Python: sweep a knob, error against time
#
# This tutorial renders one method at several values of a quality knob, measures
# each image against the path-traced reference, plots the error against the
# frame time and shows the images side by side. It is the script
# `examples/python/sweep.py` and the notebook `examples/python/sweep.ipynb`
# (the same cells). Run it from the repository root after `make`:
#
#     PYTHONPATH=build/release/python /usr/bin/python3 examples/python/sweep.py
#
# Everything happens in one process: one GL context, one loaded scene, no files.

# %%
import os

import matplotlib

matplotlib.use("Agg")  # no display needed; in Jupyter the figures show inline anyway
import matplotlib.pyplot as plt
import numpy as np

import gibench

# The repository root: where scenes/ is, from here or a folder above.
ROOT = os.getcwd()
while not os.path.isdir(os.path.join(ROOT, "scenes")) and os.path.dirname(ROOT) != ROOT:
    ROOT = os.path.dirname(ROOT)
SCENE = os.path.join(ROOT, "scenes", "cornell_box.gltf")
# Coherent shadow maps: the cube-map size of the points on an area light
METHOD, KNOB = "csm", "M_local"
VALUES = [8, 16, 64]  # coarse to the default (64)
SIZE = (32, 32)  # small so that the whole tutorial runs in seconds
FRAMES = 4

# %% [markdown]
# ## The method and its knob
# `gibench.methods()` lists what `gibench methods --json` lists: each parameter
# with its default and range, and for a declared quality knob which way is
# better and the factor of a step.

# %%
method = next(m for m in gibench.methods() if m["id"] == METHOD)
knob = next(p for p in method["params"] if p["name"] == KNOB)
values = [v for v in VALUES if knob["min"] <= v <= knob["max"]]
print(method["title"])
print("knob %s: %s; default %s, range %s..%s" % (knob["name"], knob["help"], knob["default"],
                                                 knob["min"], knob["max"]))
# the knobs gibench declares as quality knobs (more_is: which way is better)
print([p["name"] for p in method["params"] if "quality" in p])

# %% [markdown]
# ## The reference and the renders
# The reference is Embree path tracing (`gibench reference`); each render returns a
# float32 H x W x 3 array with the run's timings attached.

# %%
scene = gibench.Scene(SCENE)
ref, ref_var = scene.reference(spp=64, size=SIZE)
rows = []
images = []
for v in values:
    img = scene.render(METHOD, size=SIZE, frames=FRAMES, params={knob["name"]: v})
    m = gibench.metrics(img, ref)
    ms = img.timings["render"]["frame"]["median_ms"]
    rows.append((v, ms, m["relmse"], m["flip"]))
    images.append(img)
    print("%s=%-6s %8.2f ms/frame  relMSE %.4f  FLIP %.4f" % (knob["name"], v, ms, m["relmse"],
                                                          m["flip"]))

# %% [markdown]
# ## Error against time

# %%
fig, ax = plt.subplots(figsize=(5, 3.5))
ax.plot([r[1] for r in rows], [r[2] for r in rows], "o-")
for v, ms, rel, _ in rows:
    ax.annotate("%s=%s" % (knob["name"], v), (ms, rel), textcoords="offset points", xytext=(4, 4))
ax.set_xlabel("median frame time (ms)")
ax.set_ylabel("relMSE against the reference")
ax.set_title("%s on %s" % (METHOD, os.path.basename(SCENE)))
fig.tight_layout()

# %% [markdown]
# ## The images side by side
# Linear radiance, tone-mapped here by a clip and a gamma of 2.2 for display.

# %%
def show(x):
    return np.clip(x, 0, 1) ** (1 / 2.2)


fig, axes = plt.subplots(1, len(images) + 1, figsize=(3 * (len(images) + 1), 3))
for ax, img, (v, ms, rel, _) in zip(axes, images, rows):
    ax.imshow(show(img))
    ax.set_title("%s=%s\nrelMSE %.3f" % (knob["name"], v, rel))
    ax.axis("off")
axes[-1].imshow(show(ref))
axes[-1].set_title("reference, 64 spp")
axes[-1].axis("off")
fig.tight_layout()
out = os.environ.get("GIBENCH_EXAMPLE_OUT")
if out:  # the test and the script save the figure; a notebook shows it
    fig.savefig(out)
