"""gibench from Python: methods, scenes and renders in one process, images as numpy arrays.

    import gibench
    scene = gibench.Scene("scenes/cornell_box.gltf")
    img = scene.render("csm", size=(128, 128), frames=8, seed=1)
    img.shape, img.dtype      # (128, 128, 3) float32, rows top to bottom
    img.timings["render"]     # the run's stage timings, as gibench render --timings

The names and defaults are the CLI's (docs/commands.md); the render is the
same code as `gibench render`, so the images are the same bit for bit.
One process keeps one GL context (made on first use, on the calling
thread: use gibench from one thread) and the installed plugins; a Scene
keeps its loaded scene, its GPU upload and its last render's method
instance (the next render with the same options uses it again, for the
same image). docs/python.md has the whole API.
"""
import ctypes
import json
import os
import subprocess
import sys
import tempfile
import weakref

import numpy as np

from . import _build
from ._lib import (Error, GiError, NodeMove, ReferenceOpts, RenderOpts, RunError, UsageError,
                   check, lib, take_string)

__all__ = ["Error", "RunError", "UsageError", "Image", "Method", "Scene", "methods", "metrics", "read",
           "study", "study_runs", "write"]


class Image(np.ndarray):
    """A float32 H x W x 3 numpy array with the run's `timings` (a dict: method,
    params, prepare and render stage statistics in ms, stats; None for an image
    that was not rendered)."""

    def __new__(cls, array, timings=None):
        obj = np.asarray(array, dtype=np.float32).view(cls)
        obj.timings = timings
        return obj

    def __array_finalize__(self, obj):
        self.timings = getattr(obj, "timings", None)


def methods():
    """The installed methods as `gibench methods --json` lists them: dicts with
    id, title, citation, caps, max_bounces, params (name, type, default,
    min/max or choices, and "quality" for a quality knob) and buffers (the
    debug buffers Method.buffer gives: name, description, space)."""
    out = ctypes.c_void_p()
    err = GiError()
    check(lib.gibench_methods_json(ctypes.byref(out), ctypes.byref(err)), err)
    return json.loads(take_string(out))


def _param_text(value):
    if isinstance(value, bool):
        return "true" if value else "false"
    # 32.0 as "32": the knob steps of gibench.methods() are numbers, an int knob's too
    if isinstance(value, float) and value.is_integer():
        return str(int(value))
    return str(value)


def _size(size, cmd="render"):
    try:
        w, h = (int(v) for v in size)
    except (TypeError, ValueError):
        raise UsageError("%s: size %r is not (width, height)" % (cmd, size)) from None
    if w < 0 or h < 0 or w > 0xFFFFFFFF or h > 0xFFFFFFFF:
        raise UsageError("%s: --size '%dx%d' is not a size" % (cmd, w, h))
    return w, h


def _uint(name, value, lo, hi, cmd="render"):
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not lo <= value <= hi:
        raise UsageError("%s: --%s '%s' is not an integer in %d..%d" % (cmd, name, value, lo, hi))
    return int(value)


class _Closes:
    """What Scene and Method share: close() when the object goes, and
    `with` blocks that close on leaving."""

    def __del__(self):
        self.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


class Scene(_Closes):
    """A loaded scene and its GPU upload (gibench render --scene PATH).

    cameras: the scene's camera names (camera= takes a name or "#k");
    duration: the animation's length in seconds (0 for a static scene)."""

    def __init__(self, path):
        self.path = os.fspath(path)
        self._cwd = os.getcwd()  # where self.path is relative to, for isolate's children
        self._handle = ctypes.c_void_p()
        err = GiError()
        check(lib.gibench_scene_open(self.path.encode(), ctypes.byref(self._handle),
                                     ctypes.byref(err)), err)
        out = ctypes.c_void_p()
        check(lib.gibench_scene_info_json(self._handle, ctypes.byref(out), ctypes.byref(err)), err)
        info = json.loads(take_string(out))
        self.cameras = info["cameras"]
        self.duration = info["duration"]
        self.info = info
        self._methods = weakref.WeakSet()

    def close(self):
        """Releases the scene and its upload now (also when the object goes),
        and every Method instance made on it."""
        for m in list(getattr(self, "_methods", ())):
            m.close()
        if getattr(self, "_handle", None) and self._handle.value:
            lib.gibench_scene_close(self._handle)
            self._handle = ctypes.c_void_p()

    def _alive(self):
        if not self._handle.value:
            raise UsageError("render: the scene %s is closed" % self.path)

    def render(self, method, size=(256, 256), frames=1, seed=1, params=None, camera=None,
               time=0.0, warmup=0, exposure=0.0, no_cache=False, isolate=False, fresh=False):
        """One render as `gibench render --scene S --method M`: an Image (H x W x 3
        float32, the last frame) with .timings. isolate=True runs it in a child
        `gibench render` process, so that a crashing plugin raises RunError
        instead of taking the interpreter down.

        The scene keeps the method instance of its last render: a render with
        the same method, params, size, camera, time and no_cache (seed, frames,
        warmup and exposure may differ) uses it again from frame 0 instead of
        creating and preparing a new one; the image is the same bit for bit.
        timings["reused"] says which; fresh=True always makes a new one."""
        w, h = _size(size)
        frames = _uint("frames", frames, 1, 1000000)
        seed = _uint("seed", seed, 0, 0xFFFFFFFF)
        warmup = _uint("warmup", warmup, 0, 1000)
        texts = ["%s=%s" % (k, _param_text(v)) for k, v in (params or {}).items()]
        if isolate:
            return self._render_child(method, w, h, frames, seed, texts, camera, time, warmup,
                                      exposure, no_cache)
        self._alive()
        o, keep = _render_opts(method, w, h, frames, seed, texts, camera, time, warmup, exposure,
                               no_cache)
        o.fresh = 1 if fresh else 0
        img = np.empty((h, w, 3), dtype=np.float32)
        out = ctypes.c_void_p()
        err = GiError()
        res = lib.gibench_render(self._handle, ctypes.byref(o),
                                 img.ctypes.data_as(ctypes.POINTER(ctypes.c_float)),
                                 ctypes.byref(out), ctypes.byref(err))
        del keep
        check(res, err)
        return Image(img, json.loads(take_string(out)))

    def method(self, method, size=(256, 256), seed=1, params=None, camera=None, time=0.0,
               warmup=0, exposure=0.0, no_cache=False, isolate=False):
        """A Method: the instance created and prepared once (the options of
        render), then updated and rendered frame after frame.

        isolate=True keeps the instance in a child process (a Python
        interpreter running gibench._child, with its own GL context and its own
        copy of this scene, loaded from self.path) for the Method's whole life:
        update() and render() are requests over a pipe, images come back as
        arrays. A plugin that crashes kills only the child: that call and every
        later one on the Method raise RunError("render: the child process died
        of signal N"), and this interpreter and its other objects go on. Nodes
        moved by update(move=...) move in the child's copy of the scene only."""
        self._alive()
        cls = _ChildMethod if isolate else Method
        return cls(self, method, size, seed, params, camera, time, warmup, exposure, no_cache)

    def reference(self, spp=None, seconds=None, target_se=None, max_bounces=None,
                  size=(256, 256), seed=1, camera=None, time=0.0, threads=0, pixel="box",
                  traversal="fast", until_relmse=None, isolate=False):
        """The path-traced reference as `gibench reference`: (mean, variance), two
        H x W x 3 float32 arrays; mean.timings holds the run's stats (spp, stop,
        render_seconds, mean_rel_se, ...). Progressive: it stops at spp samples per
        pixel, after `seconds`, or at the mean relative standard error target_se
        (--target-se), or when its own estimated relMSE falls to until_relmse
        (--target-relmse: the mean over pixels and channels of the variance of
        the mean / (mean + 0.01)^2, stats["relmse_estimate"]), whichever comes
        first; with none given, 256 spp.
        max_bounces None is unlimited; time is the scene's time (--time-of-scene).
        isolate=True runs it in a child `gibench reference` process (the mean and
        the variance read back from its EXR, the stats from its --stats), so
        that a crash raises RunError instead of taking the interpreter down."""
        if not isolate:
            self._alive()
        w, h = _size(size, "reference")
        if pixel not in ("box", "center"):
            raise UsageError("reference: --pixel '%s' is not box or center" % pixel)
        if traversal not in ("fast", "robust"):
            raise UsageError("reference: --traversal '%s' is not fast or robust" % traversal)
        o = ReferenceOpts(camera=None if camera is None else str(camera).encode(), width=w,
                          height=h, seed=_uint("seed", seed, 0, 0xFFFFFFFF, "reference"),
                          threads=_uint("threads", threads, 0, 1024, "reference"),
                          time=float(time), pixel_center=pixel == "center",
                          robust_traversal=traversal == "robust")
        o.max_bounces = -1 if max_bounces is None else _uint("max-bounces", max_bounces, 0,
                                                             1000000, "reference")
        if spp is not None:
            o.spp = _uint("spp", spp, 1, 0xFFFFFFFF, "reference")
        for name, v in (("time", seconds), ("target-se", target_se),
                        ("target-relmse", until_relmse)):
            if v is not None and not (isinstance(v, (int, float)) and v > 0 and v < float("inf")):
                raise UsageError("reference: --%s '%s' is not a positive number" % (name, v))
        o.seconds = float(seconds or 0.0)
        o.target_se = float(target_se or 0.0)
        o.target_relmse = float(until_relmse or 0.0)
        if isolate:
            return self._reference_child(o, camera, pixel, traversal)
        mean = np.empty((h, w, 3), dtype=np.float32)
        var = np.empty((h, w, 3), dtype=np.float32)
        out = ctypes.c_void_p()
        err = GiError()
        fp = ctypes.POINTER(ctypes.c_float)
        check(lib.gibench_reference(self._handle, ctypes.byref(o), mean.ctypes.data_as(fp),
                                    var.ctypes.data_as(fp), ctypes.byref(out), ctypes.byref(err)),
              err)
        return Image(mean, json.loads(take_string(out))), var

    def _reference_child(self, o, camera, pixel, traversal):
        with tempfile.TemporaryDirectory(prefix="gibench-py-") as tmp:
            out = os.path.join(tmp, "reference.exr")
            stats = os.path.join(tmp, "stats.json")
            cmd = [_command(), "-q", "reference", "--scene", self.path, "--out", out,
                   "--size", "%dx%d" % (o.width, o.height), "--seed", str(o.seed),
                   "--threads", str(o.threads), "--time-of-scene", repr(float(o.time)),
                   "--pixel", pixel, "--traversal", traversal, "--stats", stats,
                   "--max-bounces", "inf" if o.max_bounces < 0 else str(o.max_bounces)]
            for flag, v in (("--spp", o.spp), ("--time", o.seconds), ("--target-se", o.target_se),
                            ("--target-relmse", o.target_relmse)):
                if v:
                    cmd += [flag, repr(v)]
            if camera is not None:
                cmd += ["--camera", str(camera)]
            p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            if p.returncode != 0:
                raise _child_error(p, "reference")
            mean, var = read(out), read(out, layer="variance")
            with open(stats) as f:
                return Image(mean, json.load(f)), np.asarray(var)

    def _render_child(self, method, w, h, frames, seed, texts, camera, time, warmup, exposure,
                      no_cache):
        with tempfile.TemporaryDirectory(prefix="gibench-py-") as tmp:
            out = os.path.join(tmp, "image.exr")
            timings = os.path.join(tmp, "timings.json")
            cmd = [_command(), "-q", "render",
                   "--scene", self.path, "--method", str(method), "--out", out,
                   "--size", "%dx%d" % (w, h), "--frames", str(frames), "--seed", str(seed),
                   "--warmup", str(warmup), "--time", repr(float(time)),
                   "--exposure", repr(float(exposure)), "--timings", timings]
            for t in texts:
                cmd += ["--param", t]
            if camera is not None:
                cmd += ["--camera", str(camera)]
            if no_cache:
                cmd.append("--no-cache")
            p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            if p.returncode != 0:
                raise _child_error(p)
            img = read(out)
            with open(timings) as f:
                return Image(img, json.load(f))


def study(study, out, jobs=None, resume=False, fresh=False, dry_run=False, as_frame=None):
    """Runs a study as `gibench study STUDY --out OUT` (each run in its own
    process, as the CLI does) and returns its runs: the records of OUT/runs.json
    as a pandas DataFrame (one row per run, nested keys flattened, e.g.
    "metrics.full.relmse") when pandas is installed (Debian's python3-pandas),
    a list of dicts otherwise. as_frame=False always gives the list;
    as_frame=True the DataFrame, or UsageError without pandas. study is a study
    file's path (its relative paths are taken from the file's folder or its
    "base") or the study itself as a dict (paths in it are relative to the
    current folder)."""
    _pandas(as_frame)  # a bad as_frame fails before the study runs
    # a dict goes on standard input ("-"), whose paths gibench takes from the current folder
    path, text = ("-", json.dumps(study)) if isinstance(study, dict) else (study, None)
    cmd = [_command(), "-q", "study", os.fspath(path), "--out", os.fspath(out)]
    if jobs is not None:
        cmd += ["--jobs", str(jobs)]
    cmd += (["--resume"] if resume else []) + (["--fresh"] if fresh else [])
    cmd += ["--dry-run"] if dry_run else []
    p = subprocess.run(cmd, input=text, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if p.returncode != 0:
        raise _child_error(p, "study")
    if dry_run:
        return p.stdout
    return study_runs(out, as_frame)


def _pandas(as_frame):
    """The pandas module when as_frame asks for a DataFrame and it is
    installed; None for a list."""
    if as_frame not in (None, True, False):
        raise UsageError("study: as_frame is None, True or False, not %r" % (as_frame,))
    if as_frame is False:
        return None
    try:
        import pandas
    except ImportError:
        if as_frame:
            raise UsageError("study: as_frame=True needs pandas (apt-get install "
                             "python3-pandas)") from None
        return None
    return pandas


def study_runs(out, as_frame=None):
    """The runs of a study's output folder OUT (its runs.json, as study()
    returns them): a pandas DataFrame when pandas is installed, a list of
    dicts otherwise or with as_frame=False (as_frame=True: UsageError without
    pandas). Reads a study run earlier, by study() or by `gibench study`."""
    pandas = _pandas(as_frame)
    path = os.path.join(os.fspath(out), "runs.json")
    try:
        with open(path) as f:
            runs = json.load(f)
    except (OSError, ValueError) as e:
        raise UsageError("study: cannot read %s: %s" % (path, getattr(e, "strerror", None) or e))
    return runs if pandas is None else pandas.json_normalize(runs)


def _command():
    """The gibench command of this build (GIBENCH_BIN overrides it)."""
    return os.environ.get("GIBENCH_BIN") or _build.COMMAND


def _render_opts(method, w, h, frames, seed, texts, camera, time, warmup, exposure, no_cache):
    """The RenderOpts of render(), and what must stay alive while it is used."""
    if w * h > (1 << 28):
        raise UsageError("render: --size '%dx%d' is too large" % (w, h))
    arr = (ctypes.c_char_p * max(1, len(texts)))(*[t.encode() for t in texts])
    o = RenderOpts(method=str(method).encode(), camera=None if camera is None else
                   str(camera).encode(), params=arr, param_count=len(texts), width=w, height=h,
                   frames=frames, warmup=warmup, seed=seed, time=float(time),
                   exposure=float(exposure), no_cache=1 if no_cache else 0)
    return o, arr


class Method(_Closes):
    """A method instance that stays alive across frames (Scene.method): one
    create() and prepare(), then update() when the scene's time or the camera
    changes and render() for more frames. What `gibench render --animate FPS`
    does between frames, driven from Python:

        m = scene.method("csm", size=(64, 64))
        for k in range(10):
            if k:
                m.update(time=k / 30)
            img = m.render()
    """

    def __init__(self, scene, method, size, seed, params, camera, time, warmup, exposure,
                 no_cache):
        w, h = _size(size)
        texts = ["%s=%s" % (k, _param_text(v)) for k, v in (params or {}).items()]
        o, keep = _render_opts(method, w, h, 1, _uint("seed", seed, 0, 0xFFFFFFFF), texts,
                               camera, time, _uint("warmup", warmup, 0, 1000), exposure,
                               no_cache)
        self.scene = scene  # the scene outlives the instance
        self.id = str(method)
        self.size = (w, h)
        self.time = float(time)
        self._handle = ctypes.c_void_p()
        err = GiError()
        check(lib.gibench_method_open(scene._handle, ctypes.byref(o), ctypes.byref(self._handle),
                                      ctypes.byref(err)), err)
        del keep
        scene._methods.add(self)

    def _alive(self):
        if not self._handle.value:
            raise UsageError("render: the %s instance is closed" % self.id)

    def update(self, time=None, camera=None, move=None):
        """Moves the scene to `time` (its animated objects, lights and camera)
        and/or switches to `camera`; the method's update() is told what changed.
        move={node: placement} places nodes by hand, as gibench view does (a
        node by name or index; a placement is a translation (x, y, z), a dict
        of "translation", "rotation" (quaternion x y z w), "scale", or a 4x4
        matrix); their objects and lights move with them.
        The next frame starts a still view's accumulation again."""
        self._alive()
        if time is not None:
            self.time = float(time)
        err = GiError()
        if move is None or time is not None or camera is not None:
            check(lib.gibench_method_update(self._handle, self.time,
                                            None if camera is None else str(camera).encode(),
                                            ctypes.byref(err)), err)
        if move is not None:
            if not isinstance(move, dict):
                raise UsageError("render: move= is a dict {node: placement}")
            arr = (NodeMove * max(1, len(move)))()
            for i, (node, place) in enumerate(move.items()):
                _node_move(arr[i], node, place)
            check(lib.gibench_method_move(self._handle, arr, len(move), ctypes.byref(err)), err)

    def render(self, frames=1):
        """`frames` more frames; the last one as an Image with .timings."""
        self._alive()
        frames = _uint("frames", frames, 1, 1000000)
        w, h = self.size
        img = np.empty((h, w, 3), dtype=np.float32)
        out = ctypes.c_void_p()
        err = GiError()
        check(lib.gibench_method_render(self._handle, frames,
                                        img.ctypes.data_as(ctypes.POINTER(ctypes.c_float)),
                                        ctypes.byref(out), ctypes.byref(err)), err)
        return Image(img, json.loads(take_string(out)))

    def buffer(self, name):
        """The method's debug buffer `name` after the last frame (as `gibench
        render --buffer NAME`; gibench.methods() lists each method's buffers):
        H x W x 3 float32, the view's size for a screen-space buffer, its own
        otherwise. UsageError for a name the method does not declare, or
        before a frame was rendered since the last update."""
        self._alive()
        rgba = ctypes.POINTER(ctypes.c_float)()
        w, h = ctypes.c_uint32(), ctypes.c_uint32()
        err = GiError()
        check(lib.gibench_method_buffer(self._handle, str(name).encode(), ctypes.byref(rgba),
                                        ctypes.byref(w), ctypes.byref(h), ctypes.byref(err)), err)
        return Image(_take_rgb(rgba, w.value, h.value))

    def close(self):
        """Destroys the instance now (also when the object goes or its scene closes)."""
        if getattr(self, "_handle", None) and self._handle.value:
            lib.gibench_method_close(self._handle)
            self._handle = ctypes.c_void_p()


class _ChildMethod(_Closes):
    """Method(isolate=True): the same interface, the instance in a child
    process (gibench/_child.py says the protocol)."""

    def __init__(self, scene, method, size, seed, params, camera, time, warmup, exposure,
                 no_cache):
        from . import _child
        self._wire = _child
        self.scene = scene
        self.id = str(method)
        self.size = _size(size)
        self.time = float(time)
        self._dead = None
        pkg_parent = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
        env = dict(os.environ)
        env["PYTHONPATH"] = os.pathsep.join(p for p in (pkg_parent, env.get("PYTHONPATH")) if p)
        self._proc = subprocess.Popen([sys.executable, "-m", "gibench._child"], env=env,
                                      cwd=scene._cwd, stdin=subprocess.PIPE, stdout=subprocess.PIPE)
        scene._methods.add(self)
        try:
            self._call("open", scene.path, method, size, seed, params, camera,
                       time, warmup, exposure, no_cache)
        except Error:
            self.close()
            raise

    def _call(self, op, *args, **kwargs):
        if self._proc is None:
            raise self._dead or UsageError("render: the %s instance is closed" % self.id)
        try:
            self._wire.write_message(self._proc.stdin, (op, args, kwargs))
            answer = self._wire.read_message(self._proc.stdout)
        except (BrokenPipeError, OSError):
            answer = None
        except BaseException:  # interrupted mid-request: the child's state is unknown
            self._proc.kill()
            self._dead = RunError("render: the child process was stopped mid-request")
            self._release()
            raise
        if answer is None:  # the child is gone: what killed it, for this call and the next
            rc = self._proc.wait()
            self._dead = RunError("render: the child process died of signal %d" % -rc if rc < 0
                                  else "render: the child process ended (exit status %d)" % rc)
            self._release()
            raise self._dead
        if answer[0] == "error":
            raise (UsageError if answer[1] == "UsageError" else RunError)(answer[2])
        return answer[1]

    def update(self, time=None, camera=None, move=None):
        """As Method.update, in the child."""
        self._call("update", time=time, camera=camera, move=move)
        if time is not None:
            self.time = float(time)

    def render(self, frames=1):
        """As Method.render, in the child."""
        img, timings = self._call("render", frames)
        return Image(img, timings)

    def buffer(self, name):
        """As Method.buffer, in the child."""
        return Image(self._call("buffer", name))

    def _release(self):
        for f in (self._proc.stdin, self._proc.stdout):
            try:
                f.close()
            except OSError:
                pass
        self._proc = None

    def close(self):
        """Ends the child (also when the object goes or its scene closes)."""
        if getattr(self, "_proc", None) is None:
            return
        # the end of the requests ends the child (its GL context torn down);
        # not waited for here, subprocess reaps it later
        self._release()


def _matrix_trs(m):
    """A 4x4 matrix (column vectors, translation in the last column) as
    translation, rotation quaternion (x y z w) and scale; no shear."""
    t = m[:3, 3]
    s = np.linalg.norm(m[:3, :3], axis=0)
    if m.shape != (4, 4) or not np.all(s > 0) or not np.allclose(m[3], [0, 0, 0, 1]):
        raise UsageError("render: move: a matrix is 4x4 with an affine last row and no zero scale")
    r = m[:3, :3] / s
    if np.linalg.det(r) < 0:
        s[0], r[:, 0] = -s[0], -r[:, 0]
    w = np.sqrt(max(0.0, 1.0 + r[0, 0] + r[1, 1] + r[2, 2])) / 2
    x = np.copysign(np.sqrt(max(0.0, 1.0 + r[0, 0] - r[1, 1] - r[2, 2])) / 2, r[2, 1] - r[1, 2])
    y = np.copysign(np.sqrt(max(0.0, 1.0 - r[0, 0] + r[1, 1] - r[2, 2])) / 2, r[0, 2] - r[2, 0])
    z = np.copysign(np.sqrt(max(0.0, 1.0 - r[0, 0] - r[1, 1] + r[2, 2])) / 2, r[1, 0] - r[0, 1])
    return {"translation": t, "rotation": (x, y, z, w), "scale": s}


def _node_move(out, node, place):
    """One entry of update(move=...) into a NodeMove."""
    out.node = str(node).encode()
    if isinstance(place, dict):
        unknown = set(place) - {"translation", "rotation", "scale"}
        if unknown:
            raise UsageError("render: move: unknown key '%s' (translation, rotation, scale)"
                             % sorted(unknown)[0])
    else:
        a = np.asarray(place, dtype=np.float64)
        if a.shape == (4, 4):
            place = _matrix_trs(a)
        elif a.shape == (3,):
            place = {"translation": a}
        else:
            raise UsageError("render: move: node %s: a placement is (x, y, z), a dict or a 4x4 "
                             "matrix" % node)
    for key, n in (("translation", 3), ("rotation", 4), ("scale", 3)):
        if key in place:
            v = np.asarray(place[key], dtype=np.float64).ravel()
            if v.shape != (n,) or not np.all(np.isfinite(v)):
                raise UsageError("render: move: node %s: %s is %d numbers" % (node, key, n))
            getattr(out, key)[:] = [float(x) for x in v]
            setattr(out, "has_" + key, 1)


def _child_error(p, cmd="render"):
    """The exception of a failed child gibench: its last 'gibench: ' line."""
    lines = [ln[len("gibench: "):] for ln in p.stderr.splitlines() if ln.startswith("gibench: ")]
    if p.returncode < 0:
        return RunError("%s: the child process died of signal %d%s" %
                        (cmd, -p.returncode, (" (" + lines[-1] + ")") if lines else ""))
    msg = lines[-1] if lines else (p.stderr.strip().splitlines() or ["exit status %d" % p.returncode])[-1]
    return UsageError(msg) if p.returncode == 2 else RunError(msg)


def metrics(test, ref, exposure=0.0, ppd=0.0, maps=False):
    """gibench diff TEST REF: a dict under diff --json's names (relmse, rmse, mse,
    mae, psnr, ssim, flip, mean_lum_*, leaked_energy, ...; None where undefined).
    maps=True adds the per-pixel maps as H x W float32 arrays: "relerr_map"
    (what diff --heatmap draws) and "flip_map" (diff --flip-map)."""
    a = np.ascontiguousarray(np.asarray(test, dtype=np.float32))
    b = np.ascontiguousarray(np.asarray(ref, dtype=np.float32))
    for x in (a, b):
        if x.ndim != 3 or x.shape[2] != 3 or x.size == 0:
            raise UsageError("metrics: an image is not H x W x 3 (shape %s)" % (x.shape,))
    if a.shape != b.shape:
        raise UsageError("image sizes differ: test %dx%d, reference %dx%d" %
                         (a.shape[1], a.shape[0], b.shape[1], b.shape[0]))
    h, w = a.shape[:2]
    fp = ctypes.POINTER(ctypes.c_float)
    rel = np.empty((h, w), dtype=np.float32) if maps else None
    flip = np.empty((h, w), dtype=np.float32) if maps else None
    out = ctypes.c_void_p()
    err = GiError()
    check(lib.gibench_metrics(a.ctypes.data_as(fp), b.ctypes.data_as(fp), w, h, float(exposure),
                              float(ppd), rel.ctypes.data_as(fp) if maps else None,
                              flip.ctypes.data_as(fp) if maps else None, ctypes.byref(out),
                              ctypes.byref(err)), err)
    m = json.loads(take_string(out))
    if maps:
        m["relerr_map"] = rel
        m["flip_map"] = flip
    return m


def read(path, layer=None):
    """An image file (EXR, PFM, PNG) read by gibench's own reader: H x W x 3 float32.
    layer names another layer of an EXR, e.g. "variance" (the variance of the
    mean that gibench reference writes beside it)."""
    rgba = ctypes.POINTER(ctypes.c_float)()
    w, h = ctypes.c_uint32(), ctypes.c_uint32()
    err = GiError()
    if layer is None:
        res = lib.gibench_image_read(os.fspath(path).encode(), ctypes.byref(rgba),
                                     ctypes.byref(w), ctypes.byref(h), ctypes.byref(err))
    else:
        res = lib.gibench_image_read_layer(os.fspath(path).encode(), str(layer).encode(),
                                           ctypes.byref(rgba), ctypes.byref(w), ctypes.byref(h),
                                           ctypes.byref(err))
    check(res, err)
    return Image(_take_rgb(rgba, w.value, h.value))


def _take_rgb(rgba, w, h):
    """The RGB of an h x w RGBA float array from libgibench, released."""
    try:
        return np.ctypeslib.as_array(rgba, shape=(h, w, 4))[:, :, :3].copy()
    finally:
        lib.gibench_free(ctypes.cast(rgba, ctypes.c_void_p))


def write(path, img, exposure=0.0):
    """Writes an H x W x 3 image as gibench render writes its --out (EXR/PFM
    linear; PNG with the exposure in stops, sRGB)."""
    a = np.ascontiguousarray(np.asarray(img, dtype=np.float32))
    if a.ndim != 3 or a.shape[2] != 3 or a.shape[0] == 0 or a.shape[1] == 0:
        raise UsageError("write: the image is not H x W x 3 (shape %s)" % (a.shape,))
    err = GiError()
    check(lib.gibench_image_write(os.fspath(path).encode(),
                                  a.ctypes.data_as(ctypes.POINTER(ctypes.c_float)),
                                  a.shape[1], a.shape[0], float(exposure), ctypes.byref(err)), err)
