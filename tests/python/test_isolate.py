"""isolate=True beyond Scene.render: Scene.reference in a child `gibench
reference`, Scene.method in a child interpreter kept across calls. The
same results as in this process; a crash raises RunError and this
interpreter goes on."""
import os

import numpy as np
import pytest

import gibench
from conftest import CORNELL, ROOT, cli_error

MOVING = os.path.join(ROOT, "scenes", "cornell_moving.gltf")


def _fake_dir():
    from gibench import _build
    fake = os.path.join(os.path.dirname(os.path.dirname(_build.COMMAND)), "tests",
                        "fake_plugins_run")
    assert os.path.exists(os.path.join(fake, "gimethod_fake_crash.so"))
    return fake


def test_isolated_reference_equals_in_process(cornell, tmp_path):
    mean, var = cornell.reference(spp=8, size=(16, 16), max_bounces=2, seed=7)
    cmean, cvar = cornell.reference(spp=8, size=(16, 16), max_bounces=2, seed=7, isolate=True)
    assert np.array_equal(mean.view(np.uint32), cmean.view(np.uint32))
    # the variance comes back from the EXR's "variance" layer (gibench.read(layer=))
    assert np.array_equal(var.view(np.uint32), cvar.view(np.uint32)) and var.max() > 0
    assert cmean.timings["spp"] == 8 and cmean.timings["stop"] == "spp"
    msg, rc = cli_error("reference", "--scene", CORNELL, "--out", str(tmp_path / "r.exr"),
                        "--size", "16x16", "--spp", "1", "--camera", "nocam")
    with pytest.raises(gibench.UsageError) as e:
        cornell.reference(spp=1, size=(16, 16), camera="nocam", isolate=True)
    assert str(e.value) == msg and rc == 2
    with pytest.raises(gibench.Error):
        gibench.read(str(tmp_path / "none.exr"), layer="variance")


def test_isolated_method_equals_in_process():
    """One child for the Method's life: an animation through it is the
    in-process one, bit for bit; errors keep the child alive."""
    scene = gibench.Scene(MOVING)
    inner = scene.method("csm", size=(16, 16))
    child = scene.method("csm", size=(16, 16), isolate=True)
    for k in range(2):
        if k:
            inner.update(time=k / 10)
            child.update(time=k / 10)
        a, b = inner.render(), child.render()
        assert np.array_equal(a.view(np.uint32), b.view(np.uint32))
    assert b.timings["method"] == "csm" and child.time == inner.time
    with pytest.raises(gibench.UsageError) as e:
        child.update(camera="nocam")
    assert "has no camera 'nocam'" in str(e.value)
    assert np.array_equal(child.render(), inner.render())  # still alive
    scene.close()  # closes the child too
    with pytest.raises(gibench.UsageError):
        child.render()


def test_isolate_survives_a_crashing_plugin(cornell, monkeypatch):
    """A plugin that dies of SIGSEGV in render(), in a child gibench render
    (Scene.render) or a child interpreter (Scene.method): RunError here, and
    this interpreter goes on."""
    # a usage error in the child is the in-process one (test_render checks
    # that one against the CLI's message); this also loads this
    # interpreter's plugins before the fake folder is named
    with pytest.raises(gibench.UsageError) as inner:
        cornell.method("nope", size=(16, 16))
    with pytest.raises(gibench.UsageError) as e:
        cornell.method("nope", size=(16, 16), isolate=True)
    assert str(e.value) == str(inner.value)
    # the children load the plugins afresh, the fake ones with them
    monkeypatch.setenv("GIBENCH_PLUGIN_PATH", _fake_dir())
    with pytest.raises(gibench.RunError) as e:
        cornell.render("fake_crash", size=(16, 16), isolate=True)
    assert str(e.value).startswith("render: the child process died of signal 11")
    m = cornell.method("fake_crash", size=(16, 16), isolate=True)
    with pytest.raises(gibench.RunError) as e:
        m.render()
    assert str(e.value) == "render: the child process died of signal 11"
    with pytest.raises(gibench.RunError) as again:  # the instance stays dead
        m.update(time=0.0)
    assert str(again.value) == str(e.value)
    m.close()
    assert cornell.render("direct", size=(16, 16)).shape == (16, 16, 3)
