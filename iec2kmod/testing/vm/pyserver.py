# SPDX-License-Identifier: MIT
"""Python fork server that runs INSIDE the QEMU guest (in the host-root chroot).

Under TCG, Python runs ~30x slower than on the host: a fresh interpreter that
imports pyroute2 costs 5-15 s.  This server imports the heavy modules once and
then forks a child per request, so a request costs a fork.  It talks over the
virtio-serial port ``iec2kmod.py`` with length-prefixed JSON frames:

    frame   = b"IK" + uint32 big-endian length + JSON
    request = {"id": n, "kind": "code"|"module"|"script", "target": str,
               "argv": [...], "cwd": str|None, "env": {...}, "timeout": s}
    reply   = {"id": n, "rc": int, "out": base64, "timed_out": bool}

plus one {"id": 0, "ready": true, "preloaded": [...], "failed": {...}} at start.
Started by :meth:`iec2kmod.testing.vm.Guest.pyrun`; stdlib only (besides preloads).
"""

from __future__ import annotations

import base64
import importlib
import json
import os
import signal
import struct
import sys
import tempfile
import time
import traceback

MAGIC = b"IK"


def read_exact(fd: int, n: int) -> bytes:
    buf = b""
    while len(buf) < n:
        chunk = os.read(fd, n - len(buf))
        if not chunk:
            raise EOFError
        buf += chunk
    return buf


def read_frame(fd: int) -> dict:
    # resynchronise on the magic if needed
    b = read_exact(fd, 1)
    while True:
        if b == b"I":
            b2 = read_exact(fd, 1)
            if b2 == b"K":
                break
            b = b2
        else:
            b = read_exact(fd, 1)
    (n,) = struct.unpack(">I", read_exact(fd, 4))
    return json.loads(read_exact(fd, n))


def write_frame(fd: int, obj: dict) -> None:
    data = json.dumps(obj).encode()
    buf = memoryview(MAGIC + struct.pack(">I", len(data)) + data)
    while buf:
        n = os.write(fd, buf)
        buf = buf[n:]


def _child(req: dict, outpath: str) -> None:
    """Runs in the forked child; never returns."""
    code = 0
    try:
        os.setsid()
        fd = os.open(outpath, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
        os.dup2(fd, 1)
        os.dup2(fd, 2)
        os.close(fd)
        null = os.open("/dev/null", os.O_RDONLY)
        os.dup2(null, 0)
        os.close(null)
        sys.stdin = open(0, "r", closefd=False)
        sys.stdout = open(1, "w", buffering=1, closefd=False)
        sys.stderr = open(2, "w", buffering=1, closefd=False)
        if req.get("cwd"):
            os.chdir(req["cwd"])
        os.environ.update(req.get("env") or {})
        kind, target, argv = req["kind"], req["target"], list(req.get("argv") or [])
        try:
            if kind == "code":
                sys.argv = ["-c"] + argv
                g = {"__name__": "__main__", "__builtins__": __builtins__}
                exec(compile(target, "<string>", "exec"), g)
            elif kind == "module":
                import runpy
                sys.argv = [target] + argv
                runpy.run_module(target, run_name="__main__", alter_sys=True)
            elif kind == "script":
                ep = req.get("entry")
                if not ep:
                    print(f"pyserver: no console script named {target!r}", file=sys.stderr)
                    code = 127
                else:
                    from importlib.metadata import EntryPoint
                    sys.argv = [target] + argv
                    rv = EntryPoint(target, ep, "console_scripts").load()()
                    code = rv if isinstance(rv, int) else (0 if rv is None else 1)
            else:
                print(f"pyserver: unknown request kind {kind!r}", file=sys.stderr)
                code = 2
        except SystemExit as e:
            if e.code is None:
                code = 0
            elif isinstance(e.code, int):
                code = e.code
            else:
                print(e.code, file=sys.stderr)
                code = 1
        except BaseException as e:
            tb = e.__traceback__.tb_next if e.__traceback__ else None   # hide this frame
            traceback.print_exception(type(e), e, tb)
            code = 1
    except BaseException:
        code = 1
    finally:
        try:
            sys.stdout.flush()
            sys.stderr.flush()
        except BaseException:
            pass
        os._exit(code & 0xFF)


def serve(port: str, preload) -> None:
    fd = os.open(port, os.O_RDWR)
    loaded, failed = [], {}
    for m in preload:
        try:
            importlib.import_module(m)
            loaded.append(m)
        except BaseException as e:       # report, keep serving
            failed[m] = f"{e.__class__.__name__}: {e}"
    write_frame(fd, {"id": 0, "ready": True, "pid": os.getpid(), "preloaded": loaded,
                     "failed": failed})
    tmpdir = tempfile.mkdtemp(prefix="pyserver-")
    scripts = None
    while True:
        try:
            req = read_frame(fd)
        except EOFError:
            time.sleep(0.1)
            continue
        outpath = os.path.join(tmpdir, "out")
        if req.get("kind") == "script":
            if scripts is None:          # resolved once, in the server, not per fork
                from importlib.metadata import entry_points
                scripts = {}
                for e in entry_points(group="console_scripts"):
                    scripts.setdefault(e.name, e.value)
            req["entry"] = scripts.get(req.get("target"))
        timeout = float(req.get("timeout") or 120)
        pid = os.fork()
        if pid == 0:
            os.close(fd)
            _child(req, outpath)
        deadline = time.monotonic() + timeout
        timed_out = False
        status = 0
        while True:
            wpid, status = os.waitpid(pid, os.WNOHANG)
            if wpid:
                break
            if time.monotonic() > deadline:
                timed_out = True
                for target in (-pid, pid):
                    try:
                        os.kill(target, signal.SIGKILL)
                    except OSError:
                        pass
                _, status = os.waitpid(pid, 0)
                break
            time.sleep(0.005)
        rc = os.waitstatus_to_exitcode(status)
        if rc < 0:
            rc = 128 - rc
        try:
            with open(outpath, "rb") as f:
                out = f.read()
            os.unlink(outpath)
        except OSError:
            out = b""
        write_frame(fd, {"id": req.get("id"), "rc": rc, "timed_out": timed_out,
                         "out": base64.b64encode(out).decode()})


def main() -> None:
    import argparse
    ap = argparse.ArgumentParser()
    ap.add_argument("port")
    ap.add_argument("--preload", default="")
    a = ap.parse_args()
    serve(a.port, [m for m in a.preload.split(",") if m])


if __name__ == "__main__":
    main()
