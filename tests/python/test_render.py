"""gibench.Scene.render against gibench render: same image bit for bit,
same errors, for every installed method."""
import os

import numpy as np
import pytest

import gibench
from conftest import CORNELL, ROOT, cli_error, run_cli

# The methods' cheapest settings where the defaults cost seconds at 32x32
# (the comparison holds at any settings; these keep the suite fast).
CHEAP = {
    "avg": {"grid": 16, "vpls": 64, "bounces": 1, "shadow_size": 8},
    "cssm_hrc": {"atlas": 8, "M": 4, "bounces": 1, "shadow_size": 16},
    "implicit_vis": {"N": 4, "bounces": 1, "direct_samples": 4},
    "vlf": {"l": 16, "N": 16, "iterations": 2},
}
# The methods this repository builds: every one must be installed and compared.
BUILT = {"avg", "csm", "cssm_hrc", "direct", "implicit_vis", "vlf"}


def test_done_when_line():
    s = gibench.Scene(CORNELL)
    img = s.render("direct", size=(64, 64))
    assert img.shape == (64, 64, 3)
    assert img.dtype == np.float32
    assert np.isfinite(img).all() and img.mean() > 0
    assert img.timings["method"] == "direct"
    assert img.timings["render"]["frame"]["median_ms"] > 0
    assert "frame" in img.timings["prepare"]


def test_methods_match_cli():
    import json
    cli = json.loads(run_cli("methods", "--json").stdout)
    py = gibench.methods()
    assert [m["id"] for m in py] == [m["id"] for m in cli]
    assert py == cli
    assert BUILT <= {m["id"] for m in py}
    csm = next(m for m in py if m["id"] == "csm")
    knob = next(p for p in csm["params"] if p["name"] == "M")
    assert knob["quality"]["more_is"] == "up" and knob["min"] == 8 and knob["max"] == 1024


@pytest.mark.parametrize("method", sorted(BUILT))
def test_bit_identical_to_cli(cornell, tmp_path, method):
    params = CHEAP.get(method, {})
    out = str(tmp_path / (method + ".exr"))
    args = ["render", "--scene", CORNELL, "--method", method, "--out", out, "--size", "32x32",
            "--frames", "2", "--seed", "3", "--no-cache"]
    for k, v in params.items():
        args += ["--param", "%s=%s" % (k, v)]
    run_cli(*args)
    cli = gibench.read(out)
    py = cornell.render(method, size=(32, 32), frames=2, seed=3, params=params, no_cache=True,
                        fresh=True)
    assert py.shape == cli.shape == (32, 32, 3)
    # bit for bit: a difference of one ulp anywhere fails
    assert np.array_equal(py.view(np.uint32), cli.view(np.uint32))
    assert py.timings["reused"] is False
    # the scene kept the instance: the same render again uses it (no new
    # prepare) and must still be the CLI's image, after it rendered frames
    again = cornell.render(method, size=(32, 32), frames=2, seed=3, params=params, no_cache=True)
    assert again.timings["reused"] is True
    assert np.array_equal(again.view(np.uint32), cli.view(np.uint32))


def test_kept_instance_rules(cornell):
    """What a kept instance serves: another seed, exposure and frame count
    (the same image as a new instance's), not another size or parameter;
    fresh=True and a failed render make a new one; implicit_vis with
    direct=traced is never kept (its ray seeds count frames since prepare)."""
    opts = dict(size=(32, 32), params={"light_samples": 2})
    cornell.render("direct", **opts)
    b = cornell.render("direct", seed=9, frames=3, exposure=1.0, **opts)
    assert b.timings["reused"] is True
    new = cornell.render("direct", seed=9, frames=3, exposure=1.0, fresh=True, **opts)
    assert new.timings["reused"] is False
    assert np.array_equal(b.view(np.uint32), new.view(np.uint32))
    assert cornell.render("direct", size=(32, 16), params=opts["params"]).timings["reused"] is False
    assert cornell.render("direct", size=(32, 16)).timings["reused"] is False
    assert cornell.render("direct", size=(32, 16), time=0.5).timings["reused"] is False
    with pytest.raises(gibench.UsageError):
        cornell.render("direct", size=(32, 16), params={"light_samples": 0})
    assert cornell.render("direct", size=(32, 16), time=0.5).timings["reused"] is True  # kept

    traced = dict(size=(16, 16), params={"direct": "traced", "N": 4, "bounces": 1,
                                          "direct_samples": 1})
    first = cornell.render("implicit_vis", **traced)
    second = cornell.render("implicit_vis", **traced)
    assert second.timings["reused"] is False
    assert np.array_equal(first.view(np.uint32), second.view(np.uint32))


def test_options_reach_the_render(cornell):
    """seed, frames, size and params change the image, so the comparison
    above would see an option dropped on the way."""
    base = cornell.render("direct", size=(32, 32), frames=1, seed=3)
    assert not np.array_equal(base, cornell.render("direct", size=(32, 32), frames=1, seed=4))
    assert not np.array_equal(base, cornell.render("direct", size=(32, 32), frames=2, seed=3))
    assert not np.array_equal(base, cornell.render("direct", size=(32, 32), frames=1, seed=3,
                                                   params={"light_samples": 1}))
    assert cornell.render("direct", size=(48, 32)).shape == (32, 48, 3)
    again = cornell.render("direct", size=(32, 32), frames=1, seed=3)
    assert np.array_equal(base, again)


def test_camera_and_time(cornell, tmp_path):
    out = str(tmp_path / "c.exr")
    run_cli("render", "--scene", CORNELL, "--method", "direct", "--out", out, "--size", "32x32",
            "--camera", "#0", "--time", "0.5")
    py = cornell.render("direct", size=(32, 32), camera="#0", time=0.5)
    assert np.array_equal(py, gibench.read(out))
    assert cornell.cameras and cornell.duration >= 0


@pytest.mark.parametrize("py_call, cli_args", [
    (lambda s: s.render("nope", size=(32, 32)),
     ["--method", "nope"]),
    (lambda s: s.render("direct", size=(32, 32), params={"light_samples": 0}),
     ["--method", "direct", "--param", "light_samples=0"]),
    (lambda s: s.render("direct", size=(32, 32), params={"bogus": 1}),
     ["--method", "direct", "--param", "bogus=1"]),
    (lambda s: s.render("direct", size=(32, 32), camera="nocam"),
     ["--method", "direct", "--camera", "nocam"]),
])
def test_errors_carry_the_cli_message(cornell, tmp_path, py_call, cli_args):
    msg, rc = cli_error("render", "--scene", CORNELL, "--out", str(tmp_path / "x.exr"),
                        "--size", "32x32", *cli_args)
    with pytest.raises(gibench.Error) as e:
        py_call(cornell)
    assert str(e.value) == msg
    assert isinstance(e.value, gibench.UsageError if rc == 2 else gibench.RunError)


def test_scene_errors(tmp_path):
    missing = str(tmp_path / "missing.gltf")
    msg, rc = cli_error("render", "--scene", missing, "--method", "direct",
                        "--out", str(tmp_path / "x.exr"))
    with pytest.raises(gibench.UsageError) as e:
        gibench.Scene(missing)
    assert str(e.value) == msg and rc == 2
    s = gibench.Scene(CORNELL)
    with pytest.raises(gibench.UsageError):
        s.render("direct", size=(0, 32))
    with pytest.raises(gibench.UsageError):
        s.render("direct", size=(32, 32), frames=0)
    s.close()
    with pytest.raises(gibench.UsageError):
        s.render("direct", size=(32, 32))


def test_read_write_round_trip(tmp_path):
    rng = np.random.default_rng(1)
    img = rng.random((8, 12, 3), dtype=np.float32) * 4
    gibench.write(str(tmp_path / "a.exr"), img)
    assert np.array_equal(gibench.read(str(tmp_path / "a.exr")), img)
    gibench.write(str(tmp_path / "a.png"), img, exposure=-1)
    png = gibench.read(str(tmp_path / "a.png"))
    assert png.shape == img.shape and png.max() <= 1.0
    with pytest.raises(gibench.Error):
        gibench.write(str(tmp_path / "a.txt"), img)
    with pytest.raises(gibench.UsageError):
        gibench.write(str(tmp_path / "b.exr"), img[:, :, :2])
    with pytest.raises(gibench.Error):
        gibench.read(str(tmp_path / "none.exr"))


def test_isolate_equals_in_process(cornell):
    a = cornell.render("direct", size=(32, 32), seed=5, isolate=True)
    b = cornell.render("direct", size=(32, 32), seed=5)
    assert np.array_equal(a, b)
    assert a.timings["method"] == "direct"
    with pytest.raises(gibench.UsageError) as e:
        cornell.render("nope", size=(32, 32), isolate=True)
    assert str(e.value).startswith("render: no method 'nope'")
