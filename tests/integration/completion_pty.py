#!/usr/bin/env python3
"""Bash completion as a user meets it (issue 33): an interactive bash in a
pseudo-terminal, with its own COMP_WORDBREAKS ('=' and ':' among them),
sources the generated completion; the test types a command line and TAB,
then Enter, and reads back the words the line held. '--param k=v' must
complete although bash splits it at '='.

usage: completion_pty.py COMPLETION.bash
"""
import os
import pty
import select
import sys
import time

# (typed, the arguments the line must hold once TAB completed it)
CASES = [
    ("gibench render --method csm --param filter=p", "render --method csm --param filter=pcf"),
    ("gibench compare --param csm.filter=n", "compare --param csm.filter=nearest"),
    ("gibench render --method csm --param fil", "render --method csm --param filter="),
    ("gibench ren", "render"),
]


def read_until(fd, marker, timeout):
    out = b""
    end = time.time() + timeout
    while marker not in out and time.time() < end:
        r, _, _ = select.select([fd], [], [], 0.2)
        if r:
            try:
                chunk = os.read(fd, 4096)
            except OSError:
                break
            if not chunk:
                break
            out += chunk
    return out


def main():
    completion = sys.argv[1]
    pid, fd = pty.fork()
    if pid == 0:
        env = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "TERM": "dumb", "HOME": "/nonexistent",
               "INPUTRC": "/dev/null", "PS1": "$ "}
        os.execvpe("bash", ["bash", "--norc", "--noprofile", "-i"], env)
    failures = 0
    try:
        setup = (f"source '{completion}'; bind 'set bell-style none'; "
                 "gibench() { printf 'ARGS<%s>\\n' \"$*\"; }; echo READY\n")
        os.write(fd, setup.encode())
        if b"READY\r\n" not in read_until(fd, b"READY\r\n", 10):
            print("FAIL: the interactive bash did not start", file=sys.stderr)
            return 1
        for typed, want in CASES:
            os.write(fd, typed.encode() + b"\t")
            time.sleep(0.5)  # readline completes before it reads the next key
            os.write(fd, b"\r")
            out = read_until(fd, b">\r\n", 10).decode(errors="replace")
            got = out[out.rfind("ARGS<") + 5:].split(">")[0] if "ARGS<" in out else None
            if got is None or got.rstrip() != want:
                print(f"FAIL: '{typed}' + TAB gave {got!r}, want {want!r}", file=sys.stderr)
                failures += 1
            else:
                print(f"ok: '{typed}' + TAB -> {got.rstrip()!r}")
    finally:
        os.write(fd, b"exit\r")
        time.sleep(0.2)
        try:
            os.kill(pid, 9)
        except OSError:
            pass
        os.waitpid(pid, 0)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
