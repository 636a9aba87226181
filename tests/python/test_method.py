"""Scene.method: an instance alive across frames, updated for an animation,
against gibench render --animate; gibench.study against gibench study."""
import json
import os
import sys

import numpy as np
import pytest

import gibench
from conftest import CORNELL, ROOT, run_cli

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


def test_buffer_equals_cli_buffer(tmp_path, cornell):
    """Method.buffer(name) is `gibench render --buffer name` of the same
    frames, bit for bit; an unknown name lists the method's buffers; a
    buffer asked for before a frame (or after an update) is refused."""
    out = str(tmp_path / "vis.exr")
    run_cli("render", "--scene", CORNELL, "--method", "csm", "--out", out, "--size", "32x32",
            "--frames", "2", "--buffer", "visibility")
    names = [b["name"] for b in next(m for m in gibench.methods() if m["id"] == "csm")["buffers"]]
    assert "visibility" in names
    m = cornell.method("csm", size=(32, 32))
    with pytest.raises(gibench.UsageError) as e:
        m.buffer("visibility")
    assert "render a frame first" in str(e.value)
    m.render(frames=2)
    vis = m.buffer("visibility")
    assert vis.shape == (32, 32, 3)
    assert np.array_equal(vis.view(np.uint32), gibench.read(out).view(np.uint32))
    assert 0.0 < float(vis.mean()) < 1.0  # a shadow term: some pixels lit, some not
    with pytest.raises(gibench.UsageError) as e:
        m.buffer("nope")
    assert "(buffers: %s)" % ", ".join(names) in str(e.value)
    m.close()


def test_study_returns_its_runs(tmp_path, monkeypatch):
    """A DataFrame with pandas (installed by the set-up: its absence fails
    here), a list of dicts without it or with as_frame=False."""
    import pandas
    study = {
        "name": "pytiny",
        "scenes": ["scenes/cornell_box_coarse.gltf"],
        "size": [16, 16],
        "frames": 2,
        "warmup": 1,
        "methods": [{"method": "direct", "params": {"light_samples": [1, 8], "env_samples": 0}}],
        "reference": {"spp": 8, "max_bounces": 2},
    }
    out = str(tmp_path / "s")
    cwd = os.getcwd()
    os.chdir(ROOT)  # paths in a study are relative to the current folder
    try:
        frame = gibench.study(study, out=out)
        bad = dict(study, frames=0)
        with pytest.raises(gibench.UsageError) as e:
            gibench.study(bad, out=str(tmp_path / "bad"))
    finally:
        os.chdir(cwd)
    # the same runs read back from the folder, as a list, with and without pandas
    runs = gibench.study_runs(out, as_frame=False)
    with monkeypatch.context() as m:
        m.setitem(sys.modules, "pandas", None)  # import pandas fails: no pandas
        hidden = gibench.study_runs(out)
        with pytest.raises(gibench.UsageError) as no_pandas:
            gibench.study_runs(out, as_frame=True)
        with pytest.raises(gibench.UsageError) as no_pandas_study:  # before running anything
            gibench.study(study, out=str(tmp_path / "none"), as_frame=True)
    assert "python3-pandas" in str(no_pandas.value)
    assert str(no_pandas_study.value) == str(no_pandas.value)
    assert not os.path.exists(str(tmp_path / "none"))
    with pytest.raises(gibench.UsageError) as e_missing:
        gibench.study_runs(str(tmp_path / "missing"))
    assert "runs.json" in str(e_missing.value)
    assert isinstance(frame, pandas.DataFrame) and len(frame) == 2
    assert isinstance(runs, list) and hidden == runs
    assert frame.to_dict("records") == pandas.json_normalize(runs).to_dict("records")
    rel = list(frame["metrics.full.relmse"])
    assert rel == [r["metrics"]["full"]["relmse"] for r in runs]
    assert sorted(r["params"] for r in runs) == ["light_samples=1,env_samples=0",
                                                 "light_samples=8,env_samples=0"]
    assert all(r["status"] == "ok" for r in runs) and all(x > 0 for x in rel)
    assert "frames" in str(e.value)


def _view_file(path, nodes):
    """A saved view of cornell_box.gltf from its camera (csm, 32x32); nodes:
    the view file's moved nodes."""
    view = {"gibench_view": 1, "scene": os.path.join(ROOT, "scenes", "cornell_box.gltf"),
            "method": "csm", "width": 32, "height": 32, "frames": 1, "seed": 1, "time": 0,
            "exposure": 0, "params": [],
            "camera": {"eye": [2.78, 2.73, -8.0], "forward": [0, 0, 1], "up": [0, 1, 0],
                       "yfov": 0.6860478808414069, "znear": 0.01, "zfar": 1000.0}}
    if nodes:
        view["nodes"] = nodes
    with open(path, "w") as f:
        json.dump(view, f)
    return str(path)


def test_move_equals_cli_view(tmp_path):
    """update(move=...) places a node as a saved view's "nodes" do for
    gibench render --view: the same image bit for bit."""
    moved = [{"node": 1, "name": "short_block", "translation": [1.5, 0.0, 1.69],
              "rotation": [0, 0, 0, 1], "scale": [1, 1, 1]}]
    out, out0 = str(tmp_path / "moved.exr"), str(tmp_path / "unmoved.exr")
    run_cli("render", "--view", _view_file(tmp_path / "v.json", moved), "--out", out)
    run_cli("render", "--view", _view_file(tmp_path / "v0.json", None), "--out", out0)
    scene = gibench.Scene(CORNELL)  # its own: a move stays in the scene
    kept = scene.render("csm", size=(32, 32))  # an instance the scene keeps
    m = scene.method("csm", size=(32, 32))
    still = m.render()
    assert np.array_equal(still.view(np.uint32), gibench.read(out0).view(np.uint32))
    assert np.array_equal(kept, still)
    m.update(move={"short_block": (1.5, 0.0, 1.69)})
    img = m.render()
    assert np.array_equal(img.view(np.uint32), gibench.read(out).view(np.uint32))
    assert not np.array_equal(img, still)
    # a render after the move is a new instance prepared for the moved scene
    # (the kept one knew the block as static), the image of the moved Method
    fresh = scene.render("csm", size=(32, 32))
    assert fresh.timings["reused"] is False
    assert np.array_equal(fresh.view(np.uint32), img.view(np.uint32))
    # by index and as a 4x4 matrix: the same placement, the same image
    mat = np.eye(4)
    mat[:3, 3] = (1.5, 0.0, 1.69)
    m.update(move={1: mat})
    assert np.array_equal(m.render(), img)
    for move, msg in (({"nope": (0, 0, 0)}, "has no node 'nope'"),
                      ({"short_block": {"rotation": (0, 0, 0, 2)}}, "not a unit quaternion"),
                      ({"short_block": (1, 2)}, "a placement is"),
                      ({"camera": {"scale": (1, 1)}}, "scale is 3 numbers")):
        with pytest.raises(gibench.UsageError) as e:
            m.update(move=move)
        assert msg in str(e.value)
    m.close()
    scene.close()


def test_move_a_light(tmp_path):
    """Moving the light's node lights the box differently."""
    scene = gibench.Scene(CORNELL)
    m = scene.method("csm", size=(32, 32))
    still = m.render()
    m.update(move={"light": {"translation": (2.78, 3.5, 2.795)}})
    assert not np.array_equal(m.render(), still)
    m.close()
    scene.close()


def test_first_move_reprepares():
    """The first update(move=...) of an instance prepared with every object
    static makes it again for the moved objects (gibench_method_move).
    cssm_hrc is the method whose prepare() depends on what moves (its
    moving-object mode; without the new prepare its update() refuses the
    move), at cheap settings on the 36-triangle box. The image after the
    move equals, within float rounding, that of a new instance prepared for
    the moved scene (the scene keeps the placement, so Scene.render(fresh=
    True) makes one): the remade instance draws the mover's maps at the old
    placement and moves them; by hand 41 of 256 pixels differ, by at most
    1.5e-8 (1e-7 relative), against a change of 0.24 that the move makes."""
    scene = gibench.Scene(os.path.join(ROOT, "scenes", "cornell_box_coarse.gltf"))
    opts = dict(size=(16, 16), params={"atlas": 8, "M": 4, "bounces": 1, "shadow_size": 16,
                                       "csm_M": 8, "csm_points": 4, "csm_samples": 1,
                                       "env_samples": 1})
    m = scene.method("cssm_hrc", **opts)
    still = m.render()
    m.update(move={"short_block": (1.5, 0.0, 1.69)})
    moved = m.render()
    assert moved.timings["stats"]["moving_objects"] == 1
    fresh = scene.render("cssm_hrc", fresh=True, **opts)
    rel = np.abs(moved - fresh) / (np.abs(fresh) + 1e-3)
    assert rel.max() <= 1e-5
    assert np.abs(moved - still).max() > 0.1  # the block moved: far above the bound
    m.close()
    scene.close()
