"""ctypes bindings of libgibench (harness/api/include/gi/gibench.h)."""
import ctypes
import os

from . import _build

GI_ERR_INVALID_ARGUMENT = 1
GI_ERR_UNSUPPORTED = 2


class Error(Exception):
    """A gibench failure; str() is the one line the CLI prints after 'gibench: '."""


class UsageError(Error, ValueError):
    """Bad usage or input (the CLI's exit status 2)."""


class RunError(Error, RuntimeError):
    """A failure while running (the CLI's exit status 1), or a crashed child."""


for _cls in (Error, UsageError, RunError):
    _cls.__module__ = "gibench"


class GiError(ctypes.Structure):
    _fields_ = [("text", ctypes.c_char * 512)]


class RenderOpts(ctypes.Structure):
    """gibench_render_opts, field for field."""
    _fields_ = [
        ("method", ctypes.c_char_p),
        ("camera", ctypes.c_char_p),
        ("params", ctypes.POINTER(ctypes.c_char_p)),
        ("param_count", ctypes.c_uint32),
        ("width", ctypes.c_uint32),
        ("height", ctypes.c_uint32),
        ("frames", ctypes.c_uint32),
        ("warmup", ctypes.c_uint32),
        ("seed", ctypes.c_uint32),
        ("time", ctypes.c_float),
        ("exposure", ctypes.c_float),
        ("no_cache", ctypes.c_int),
        ("fresh", ctypes.c_int),
    ]


class NodeMove(ctypes.Structure):
    """gibench_node_move, field for field."""
    _fields_ = [
        ("node", ctypes.c_char_p),
        ("has_translation", ctypes.c_int), ("has_rotation", ctypes.c_int),
        ("has_scale", ctypes.c_int),
        ("translation", ctypes.c_float * 3), ("rotation", ctypes.c_float * 4),
        ("scale", ctypes.c_float * 3),
    ]


class ReferenceOpts(ctypes.Structure):
    """gibench_reference_opts, field for field."""
    _fields_ = [
        ("camera", ctypes.c_char_p),
        ("width", ctypes.c_uint32),
        ("height", ctypes.c_uint32),
        ("spp", ctypes.c_uint64),
        ("seconds", ctypes.c_double),
        ("target_se", ctypes.c_double),
        ("max_bounces", ctypes.c_int),
        ("seed", ctypes.c_uint32),
        ("threads", ctypes.c_uint32),
        ("time", ctypes.c_float),
        ("pixel_center", ctypes.c_int),
        ("robust_traversal", ctypes.c_int),
        ("target_relmse", ctypes.c_double),
    ]


def _load():
    path = os.environ.get("GIBENCH_LIBRARY") or _build.LIBRARY
    lib = ctypes.CDLL(path)
    P = ctypes.c_void_p
    err = ctypes.POINTER(GiError)
    sigs = {
        "gibench_methods_json": ([ctypes.POINTER(P), err], ctypes.c_int),
        "gibench_scene_open": ([ctypes.c_char_p, ctypes.POINTER(P), err], ctypes.c_int),
        "gibench_scene_close": ([P], None),
        "gibench_scene_info_json": ([P, ctypes.POINTER(P), err], ctypes.c_int),
        "gibench_render": ([P, ctypes.POINTER(RenderOpts), ctypes.POINTER(ctypes.c_float),
                            ctypes.POINTER(P), err], ctypes.c_int),
        "gibench_image_read": ([ctypes.c_char_p, ctypes.POINTER(ctypes.POINTER(ctypes.c_float)),
                                ctypes.POINTER(ctypes.c_uint32), ctypes.POINTER(ctypes.c_uint32),
                                err], ctypes.c_int),
        "gibench_image_read_layer": ([ctypes.c_char_p, ctypes.c_char_p,
                                      ctypes.POINTER(ctypes.POINTER(ctypes.c_float)),
                                      ctypes.POINTER(ctypes.c_uint32),
                                      ctypes.POINTER(ctypes.c_uint32), err], ctypes.c_int),
        "gibench_image_write": ([ctypes.c_char_p, ctypes.POINTER(ctypes.c_float), ctypes.c_uint32,
                                 ctypes.c_uint32, ctypes.c_float, err], ctypes.c_int),
        "gibench_reference": ([P, ctypes.POINTER(ReferenceOpts), ctypes.POINTER(ctypes.c_float),
                               ctypes.POINTER(ctypes.c_float), ctypes.POINTER(P), err],
                              ctypes.c_int),
        "gibench_metrics": ([ctypes.POINTER(ctypes.c_float), ctypes.POINTER(ctypes.c_float),
                             ctypes.c_uint32, ctypes.c_uint32, ctypes.c_float, ctypes.c_float,
                             ctypes.POINTER(ctypes.c_float), ctypes.POINTER(ctypes.c_float),
                             ctypes.POINTER(P), err], ctypes.c_int),
        "gibench_method_open": ([P, ctypes.POINTER(RenderOpts), ctypes.POINTER(P), err],
                                ctypes.c_int),
        "gibench_method_update": ([P, ctypes.c_float, ctypes.c_char_p, err], ctypes.c_int),
        "gibench_method_move": ([P, ctypes.POINTER(NodeMove), ctypes.c_uint32, err],
                                ctypes.c_int),
        "gibench_method_render": ([P, ctypes.c_uint32, ctypes.POINTER(ctypes.c_float),
                                   ctypes.POINTER(P), err], ctypes.c_int),
        "gibench_method_buffer": ([P, ctypes.c_char_p, ctypes.POINTER(ctypes.POINTER(ctypes.c_float)),
                                   ctypes.POINTER(ctypes.c_uint32), ctypes.POINTER(ctypes.c_uint32),
                                   err], ctypes.c_int),
        "gibench_method_close": ([P], None),
        "gibench_free": ([P], None),
    }
    for name, (args, res) in sigs.items():
        fn = getattr(lib, name)
        fn.argtypes = args
        fn.restype = res
    return lib


lib = _load()


def check(res, err):
    """Raises the exception of a gi_result with the message of its gi_error."""
    if res == 0:
        return
    text = err.text.decode("utf-8", "replace")
    if res in (GI_ERR_INVALID_ARGUMENT, GI_ERR_UNSUPPORTED):
        raise UsageError(text)
    raise RunError(text)


def take_string(ptr):
    """The text of a char * from libgibench, released."""
    try:
        return ctypes.string_at(ptr.value).decode("utf-8") if ptr.value else ""
    finally:
        lib.gibench_free(ptr)
