"""Scene.method: an instance alive across frames, updated for an animation,
against gibench render --animate; gibench.study against gibench study."""
import os

import numpy as np
import pytest

import gibench
from conftest import ROOT, run_cli

MOVING = os.path.join(ROOT, "scenes", "cornell_moving.gltf")


# csm rebuilds its maps of what moves in update(); cssm_hrc too, but costs 20 s here
@pytest.mark.parametrize("method", ["csm"])
def test_animation_equals_cli_animate(tmp_path, method):
    out = str(tmp_path / "anim.exr")
    run_cli("render", "--scene", MOVING, "--method", method, "--out", out, "--size", "32x32",
            "--frames", "4", "--animate", "10")
    scene = gibench.Scene(MOVING)
    assert scene.duration > 0
    m = scene.method(method, size=(32, 32))
    first = m.render()
    for k in range(1, 4):
        m.update(time=k / 10)
        img = m.render()
    assert np.array_equal(img.view(np.uint32), gibench.read(out).view(np.uint32))
    assert not np.array_equal(first, img)  # the objects moved
    assert img.timings["method"] == method
    scene.close()
    with pytest.raises(gibench.UsageError):
        m.render()


def test_method_frames_accumulate_like_a_render(cornell):
    """render(frames=1) twice on one instance is render(frames=2)."""
    m = cornell.method("direct", size=(32, 32), seed=3)
    m.render()
    two = m.render()
    assert np.array_equal(two, cornell.render("direct", size=(32, 32), seed=3, frames=2))
    m.update(time=0.0)  # an update starts the accumulation again
    assert np.array_equal(m.render(), cornell.render("direct", size=(32, 32), seed=3))
    with pytest.raises(gibench.UsageError) as e:
        m.update(camera="nocam")
    assert "has no camera 'nocam'" in str(e.value)
    m.close()


def test_study_returns_its_runs(tmp_path):
    study = {
        "name": "pytiny",
        "scenes": ["scenes/cornell_box_coarse.gltf"],
        "size": [16, 16],
        "frames": 2,
        "warmup": 1,
        "methods": [{"method": "direct", "params": {"light_samples": [1, 8], "env_samples": 0}}],
        "reference": {"spp": 8, "max_bounces": 2},
    }
    cwd = os.getcwd()
    os.chdir(ROOT)  # paths in a study are relative to the current folder
    try:
        runs = gibench.study(study, out=str(tmp_path / "s"))
        bad = dict(study, frames=0)
        with pytest.raises(gibench.UsageError) as e:
            gibench.study(bad, out=str(tmp_path / "bad"))
    finally:
        os.chdir(cwd)
    if not isinstance(runs, list):  # pandas present: one row per run
        runs = runs.to_dict("records")
        rel = [r["metrics.full.relmse"] for r in runs]
    else:
        rel = [r["metrics"]["full"]["relmse"] for r in runs]
    assert sorted(r["params"] for r in runs) == ["light_samples=1,env_samples=0",
                                                 "light_samples=8,env_samples=0"]
    assert all(r["status"] == "ok" for r in runs) and all(x > 0 for x in rel)
    assert "frames" in str(e.value)
