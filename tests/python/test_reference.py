"""Scene.reference and gibench.metrics against gibench reference and gibench diff."""
import json
import math

import numpy as np
import pytest

import gibench
from conftest import CORNELL, cli_error, run_cli


def test_reference_equals_cli(cornell, tmp_path):
    out = str(tmp_path / "ref.exr")
    run_cli("reference", "--scene", CORNELL, "--out", out, "--size", "32x32", "--spp", "16",
            "--max-bounces", "2", "--seed", "7")
    mean, var = cornell.reference(spp=16, size=(32, 32), max_bounces=2, seed=7)
    assert mean.shape == var.shape == (32, 32, 3)
    assert np.array_equal(mean.view(np.uint32), gibench.read(out).view(np.uint32))
    assert mean.timings["spp"] == 16 and mean.timings["stop"] == "spp"
    assert (var >= 0).all() and var.max() > 0
    # the seed and the bounces reach the path tracer
    other, _ = cornell.reference(spp=16, size=(32, 32), max_bounces=2, seed=8)
    assert not np.array_equal(mean, other)
    fewer, _ = cornell.reference(spp=16, size=(32, 32), max_bounces=0, seed=7)
    assert fewer.mean() < mean.mean()


def test_progressive_target_se_stops_where_the_cli_stops(cornell, tmp_path):
    out, stats = str(tmp_path / "ref.exr"), str(tmp_path / "stats.json")
    run_cli("reference", "--scene", CORNELL, "--out", out, "--size", "32x32", "--target-se",
            "0.2", "--max-bounces", "2", "--stats", stats)
    mean, _ = cornell.reference(target_se=0.2, size=(32, 32), max_bounces=2)
    with open(stats) as f:
        cli_spp = json.load(f)["spp"]
    assert mean.timings["stop"] == "target-se" and mean.timings["spp"] == cli_spp
    assert mean.timings["mean_rel_se"] <= 0.2
    assert np.array_equal(mean, gibench.read(out))
    timed, _ = cornell.reference(seconds=0.2, size=(16, 16), max_bounces=1)
    assert timed.timings["stop"] == "time" and timed.timings["spp"] >= 1


def test_until_relmse_stops_at_its_checkpoint(cornell, tmp_path):
    """until_relmse (--target-relmse): the estimate is relMSE's convention on
    the returned mean and variance; it is <= X where the run stops and > X at
    the checkpoint before (replayed: the image after n spp does not depend on
    the passes); a smaller X takes more samples; the CLI stops at the same."""
    x, kw = 0.05, dict(size=(16, 16), max_bounces=2)
    mean, var = cornell.reference(until_relmse=x, **kw)
    est = mean.timings["relmse_estimate"]
    assert mean.timings["stop"] == "target-relmse" and est <= x
    assert np.isclose(est, np.mean(var.astype(np.float64) / (mean + 0.01) ** 2), rtol=1e-4)
    spp, checkpoints = 4, []
    while True:  # ref_progressive.c's checkpoints: 4, then 10% past the 1/n law, <= doubling
        checkpoints.append(spp)
        rm = cornell.reference(spp=spp, **kw)[0].timings["relmse_estimate"]
        if rm <= x:
            break
        want = 1.1 * spp * (math.sqrt(rm) / math.sqrt(x)) * (math.sqrt(rm) / math.sqrt(x))
        spp = max(spp + 1, 2 * spp if want > 2 * spp else math.ceil(want))
    assert len(checkpoints) >= 2 and checkpoints[-1] == mean.timings["spp"]
    assert cornell.reference(spp=checkpoints[-2], **kw)[0].timings["relmse_estimate"] > x
    finer, _ = cornell.reference(until_relmse=x / 4, **kw)
    assert finer.timings["spp"] > mean.timings["spp"]
    out, stats = str(tmp_path / "ref.exr"), str(tmp_path / "stats.json")
    run_cli("reference", "--scene", CORNELL, "--out", out, "--size", "16x16", "--target-relmse",
            str(x), "--max-bounces", "2", "--stats", stats)
    with open(stats) as f:
        st = json.load(f)
    assert st["spp"] == mean.timings["spp"] and st["stop"] == "target-relmse"
    assert np.array_equal(mean, gibench.read(out))
    msg, rc = cli_error("reference", "--scene", CORNELL, "--out", out, "--target-relmse", "0")
    with pytest.raises(gibench.UsageError) as e:
        cornell.reference(until_relmse=0, size=(16, 16))
    assert str(e.value) == msg and rc == 2


def test_reference_errors(cornell, tmp_path):
    msg, rc = cli_error("reference", "--scene", CORNELL, "--out", str(tmp_path / "r.exr"),
                        "--camera", "nocam", "--size", "16x16", "--spp", "1")
    with pytest.raises(gibench.UsageError) as e:
        cornell.reference(spp=1, size=(16, 16), camera="nocam")
    assert str(e.value) == msg and rc == 2
    with pytest.raises(gibench.UsageError):
        cornell.reference(target_se=-1, size=(16, 16))
    with pytest.raises(gibench.UsageError):
        cornell.reference(spp=4, size=(0, 16))


def test_metrics_equal_diff(cornell, tmp_path):
    img = cornell.render("direct", size=(32, 32), seed=2)
    ref, _ = cornell.reference(spp=8, size=(32, 32), max_bounces=1)
    gibench.write(str(tmp_path / "t.exr"), img)
    gibench.write(str(tmp_path / "r.exr"), ref)
    cli = json.loads(run_cli("diff", str(tmp_path / "t.exr"), str(tmp_path / "r.exr"),
                             "--json").stdout)
    m = gibench.metrics(img, ref, maps=True)
    for k in ("relmse", "rmse", "mse", "mae", "psnr", "ssim", "flip", "mean_lum_diff_pct",
              "leaked_energy"):
        assert m[k] == cli[k], k
    assert m["relmse"] > 0
    assert m["relerr_map"].shape == m["flip_map"].shape == (32, 32)
    assert np.isclose(np.nanmean(m["flip_map"]), m["flip"], rtol=1e-5)
    rel = np.mean(np.abs(img - ref) / (ref + 0.01), axis=2)
    assert np.allclose(m["relerr_map"], rel, rtol=1e-4, atol=1e-6)
    same = gibench.metrics(img, img)
    assert same["relmse"] == 0 and same["ssim"] == 1
    with pytest.raises(gibench.UsageError) as e:
        gibench.metrics(img, ref[:16])
    assert "image sizes differ" in str(e.value)
