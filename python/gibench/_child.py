"""The child process of an isolated Method (Scene.method(..., isolate=True)).

The parent starts `python -m gibench._child` and keeps it for the instance's
life: one Scene and one Method live here, in this process's GL context, and
a plugin that crashes takes only this process down. Requests come on stdin
and answers go back on the stdout the parent gave; both are pickled tuples
behind a 4-byte length:

    request  (op, args, kwargs), op one of "open", "update", "render"
    answer   ("ok", value) | ("error", "UsageError" or "RunError", message)

The end of the requests (the parent closed the pipe: Method.close, or the
parent died) ends this process.

A plugin that prints to stdout must not break the answers, so this process's
fd 1 is pointed at stderr and the answers go out on a copy of the old one.
"""
import os
import pickle
import struct
import sys


def read_message(f):
    """One length-prefixed pickled object from f; None at end of file."""
    head = f.read(4)
    if len(head) < 4:
        return None
    (n,) = struct.unpack("<I", head)
    body = f.read(n)
    if len(body) < n:
        return None
    return pickle.loads(body)


def write_message(f, obj):
    body = pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL)
    f.write(struct.pack("<I", len(body)) + body)
    f.flush()


def _serve(requests, answers):
    import numpy as np

    import gibench  # after the fd switch: plugins print as they load

    scene = method = None
    while True:
        req = read_message(requests)
        if req is None:
            return
        op, args, kwargs = req
        try:
            if op == "open":
                scene = gibench.Scene(args[0])
                method = scene.method(*args[1:], **kwargs)
                value = None
            elif op == "update":
                value = method.update(*args, **kwargs)
            elif op == "render":
                img = method.render(*args, **kwargs)
                value = (np.asarray(img), img.timings)
            elif op == "buffer":
                value = np.asarray(method.buffer(*args))
            else:
                raise gibench.RunError("isolate: unknown request '%s'" % op)
            answer = ("ok", value)
        except gibench.Error as e:
            answer = ("error", type(e).__name__, str(e))
        except Exception as e:  # a bad argument: the caller's exception, not a dead child
            answer = ("error", "UsageError", "%s: %s" % (type(e).__name__, e))
        write_message(answers, answer)


def main():
    answers = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    _serve(sys.stdin.buffer, answers)


if __name__ == "__main__":
    main()
