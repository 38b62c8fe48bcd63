# SPDX-License-Identifier: MIT
"""Reproducible module builds in a container, through the docker SDK.

The image is made locally, never pulled: ``containers/build-rootfs.sh``
debootstraps Debian bookworm with the toolchain and exactly the host's
PREEMPT_RT kbuild headers, the root file system is tarred and ``docker
import``-ed.  The tag is ``iec2kmod-build:<hash>``, the hash covering every file
of ``containers/`` (but ``*.md``) and the headers' release and version, so an image is rebuilt
only when the recipe changes.

    from iec2kmod import container
    tag = container.ensure_image()                    # minutes the first time
    res = container.build_modules("/path/to/moddir")  # make ... W=1 modules
    print(res.exit_code, res.output)

Command line: ``python -m iec2kmod.container ensure | tag | run DIR -- CMD...``.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import fcntl
import glob
import hashlib
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
from typing import Callable, Dict, List, Optional, Sequence, Tuple

from . import buildcache, kbuild

IMAGE_REPO = "iec2kmod-build"
SUITE = "bookworm"


class ContainerError(RuntimeError):
    """The container build cannot be done; the message says why and what to do."""


@dataclasses.dataclass
class ContainerResult:
    exit_code: int
    output: str          # stdout and stderr
    duration: float
    image: str
    command: str
    cached: bool = False     # restored from the build cache (iec2kmod/buildcache.py)

    @property
    def ok(self) -> bool:
        return self.exit_code == 0


def recipe_dir() -> str:
    d = os.environ.get("IEC2KMOD_CONTAINER_RECIPE") or os.path.join(
        os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "containers")
    if not os.path.isfile(os.path.join(d, "build-rootfs.sh")):
        try:  # an installed (non-editable) copy ships it as package data
            from .resources import containers_root
            d = str(containers_root())
        except FileNotFoundError:
            pass
    if not os.path.isfile(os.path.join(d, "build-rootfs.sh")):
        raise ContainerError(f"container recipe not found ({d}/build-rootfs.sh)")
    return d


def _headers() -> Tuple[str, str, str]:
    """(kdir, kernel release, Debian version of linux-headers-<release>)."""
    try:
        kdir = kbuild.find_kdir()
        rel = kbuild.kernel_release(kdir)
    except kbuild.KbuildError as e:
        raise ContainerError(str(e)) from None
    try:
        ver = subprocess.run(["dpkg-query", "-W", "-f=${Version}", f"linux-headers-{rel}"],
                             capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        raise ContainerError(f"cannot find the version of package linux-headers-{rel} "
                             "(dpkg-query failed); apt-get install linux-headers-rt-amd64")
    return kdir, rel, ver


def _image_config(release: str) -> list:
    """The ``docker import`` changes that configure the image (the rest of
    what makes it is build-rootfs.sh and the headers' release and version)."""
    return ["ENV PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin",
            "ENV LANG=C.UTF-8",
            f"ENV IEC2KMOD_KDIR=/usr/src/linux-headers-{release}",
            'CMD ["/bin/bash"]']


def recipe_hash(release: Optional[str] = None, version: Optional[str] = None) -> str:
    """The image's identity: a hash of exactly what makes the image, namely
    the recipe's files (build-rootfs.sh and anything else it reads, but not
    its documentation, ``*.md``, nor the Python package marker ``*.py`` that
    installs the directory as ``iec2kmod.containers``: editing those does not
    change the image and must not rebuild it), the suite, the headers'
    release and version, and the image configuration set at import."""
    if release is None or version is None:
        _, release, version = _headers()
    h = hashlib.sha256()
    d = recipe_dir()
    for root, dirs, files in os.walk(d):
        dirs[:] = sorted(x for x in dirs if x != "__pycache__")
        for fn in sorted(files):
            if fn.endswith((".md", ".py", ".pyc")):   # not read by the recipe
                continue
            p = os.path.join(root, fn)
            h.update(os.path.relpath(p, d).encode() + b"\0")
            with open(p, "rb") as f:
                h.update(f.read() + b"\0")
    h.update(f"{SUITE}\0{release}\0{version}\0".encode())
    h.update("\0".join(_image_config(release)).encode())
    return h.hexdigest()[:16]


def image_tag() -> str:
    return f"{IMAGE_REPO}:{recipe_hash()}"


def docker_client():
    try:
        import docker
    except ImportError:
        raise ContainerError("the docker Python SDK is missing: pip install docker "
                             "(or run scripts/setup.sh)") from None
    try:
        client = docker.from_env(timeout=120)
        client.ping()
    except Exception as e:          # docker.errors.DockerException, requests errors
        raise ContainerError(
            f"cannot reach the docker daemon ({e.__class__.__name__}: {e}); start it "
            "(scripts/setup.sh starts dockerd) or set DOCKER_HOST") from None
    return client


def _image_exists(client, tag: str) -> bool:
    import docker
    try:
        client.images.get(tag)
        return True
    except docker.errors.ImageNotFound:
        return False


def debian_mirrors(paths: Optional[Sequence[str]] = None) -> Tuple[str, str]:
    """(main mirror, security mirror) for bookworm from this machine's apt
    sources (one-line ``.list`` and deb822 ``.sources`` files)."""
    if paths is None:
        paths = ["/etc/apt/sources.list"] + sorted(
            glob.glob("/etc/apt/sources.list.d/*.list")
            + glob.glob("/etc/apt/sources.list.d/*.sources"))
    entries: List[Tuple[str, List[str]]] = []      # (uri, suites)
    for p in paths:
        try:
            with open(p) as f:
                text = f.read()
        except OSError:
            continue
        if p.endswith(".sources"):
            for stanza in re.split(r"\n\s*\n", text):
                fields: Dict[str, str] = {}
                for line in stanza.splitlines():
                    if line.startswith("#") or ":" not in line:
                        continue
                    k, v = line.split(":", 1)
                    fields[k.strip().lower()] = v.strip()
                if "deb" not in fields.get("types", "").split():
                    continue
                if fields.get("enabled", "yes").lower() == "no":
                    continue
                for uri in fields.get("uris", "").split():
                    entries.append((uri, fields.get("suites", "").split()))
        else:
            for line in text.splitlines():
                line = re.sub(r"\[[^\]]*\]", " ", line.split("#", 1)[0]).split()
                if len(line) >= 3 and line[0] == "deb":
                    entries.append((line[1], [line[2]]))
    main = next((u for u, s in entries if SUITE in s), None)
    sec = next((u for u, s in entries if f"{SUITE}-security" in s or f"{SUITE}/updates" in s),
               None)
    if not main:
        raise ContainerError(f"no Debian '{SUITE}' mirror found in /etc/apt/sources.list(.d)")
    return main.rstrip("/"), (sec or "http://security.debian.org/debian-security").rstrip("/")


@contextlib.contextmanager
def _lock(path: str):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        fcntl.flock(f, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(f, fcntl.LOCK_UN)


def _cache_dir() -> str:
    return os.path.join(os.environ.get("IEC2KMOD_CACHE", "/var/cache/iec2kmod"), "container")


def ensure_image(*, log: Callable[[str], None] = print, rebuild: bool = False) -> str:
    """Return the tag of the build image, building it first if it is missing
    (needs root and debootstrap; takes minutes)."""
    client = docker_client()
    _, rel, ver = _headers()
    tag = f"{IMAGE_REPO}:{recipe_hash(rel, ver)}"
    if not rebuild and _image_exists(client, tag):
        log(f"container image present: {tag}")
        return tag
    with _lock(os.path.join(_cache_dir(), "build.lock")):
        if not rebuild and _image_exists(client, tag):
            log(f"container image present: {tag}")
            return tag
        if os.geteuid() != 0:
            raise ContainerError(f"building the container image {tag} needs root "
                                 "(debootstrap); run scripts/setup.sh as root")
        if not shutil.which("debootstrap"):
            raise ContainerError("debootstrap not found: apt-get install debootstrap "
                                 "(or run scripts/setup.sh)")
        mirror, secmirror = debian_mirrors()
        log(f"building container image {tag} (debootstrap {SUITE} from {mirror}, "
            f"linux-headers-{rel}={ver}); this takes a few minutes")
        t0 = time.monotonic()
        work = tempfile.mkdtemp(prefix="build-", dir=_cache_dir())
        try:
            rootfs = os.path.join(work, "rootfs")
            p = subprocess.run([os.path.join(recipe_dir(), "build-rootfs.sh"), rootfs, mirror,
                                secmirror, rel, ver], stdin=subprocess.DEVNULL)
            if p.returncode != 0:
                raise ContainerError(f"containers/build-rootfs.sh failed (exit {p.returncode})")
            tarball = os.path.join(work, "rootfs.tar")
            log("packing the root file system")
            p = subprocess.run(["tar", "--numeric-owner", "--xattrs", "-C", rootfs, "-cf",
                                tarball, "."], stdin=subprocess.DEVNULL,
                               stderr=subprocess.PIPE, text=True)
            if p.returncode != 0:
                raise ContainerError(f"tar of the container root failed: {p.stderr.strip()}")
            log(f"docker import -> {tag}")
            repo, _, t = tag.partition(":")
            client.api.import_image(
                src=tarball, repository=repo, tag=t,
                changes=_image_config(rel) + [
                    f"LABEL org.iec2kmod.recipe={tag.split(':')[1]} "
                    f"org.iec2kmod.kernel={rel} org.iec2kmod.headers-version={ver}"])
            if not _image_exists(client, tag):
                raise ContainerError(f"docker import did not create {tag}")
        finally:
            subprocess.run(["rm", "-rf", "--one-file-system", work])
        log(f"container image {tag} built in {time.monotonic() - t0:.0f} s")
        return tag


def run_in_container(workdir: str, command: str, *, image: Optional[str] = None,
                     timeout: float = 900, env: Optional[Dict[str, str]] = None,
                     as_host_user: bool = True) -> ContainerResult:
    """Run shell *command* in the build image with host directory *workdir*
    bind-mounted read-write at the same path (and as the working directory).
    No network.  Returns exit code and output; raises :class:`ContainerError`
    only when the container cannot run or times out (it is then killed)."""
    import requests
    workdir = os.path.realpath(workdir)
    if not os.path.isdir(workdir):
        raise ContainerError(f"{workdir} is not a directory")
    client = docker_client()
    if image is None:
        image = image_tag()
        if not _image_exists(client, image):
            raise ContainerError(f"container image {image} is missing: run scripts/setup.sh "
                                 "(or python -m iec2kmod.container ensure)")
    t0 = time.monotonic()
    kw = {}
    if as_host_user:
        kw["user"] = f"{os.getuid()}:{os.getgid()}"
    try:
        c = client.containers.run(
            image, ["/bin/sh", "-c", command], detach=True, network_disabled=True,
            volumes={workdir: {"bind": workdir, "mode": "rw"}}, working_dir=workdir,
            environment=dict(env or {}, HOME="/tmp"), labels={"org.iec2kmod.build": "1"},
            **kw)
    except Exception as e:
        raise ContainerError(f"cannot start a container from {image}: {e}") from None
    try:
        try:
            status = c.wait(timeout=timeout)
        except (requests.exceptions.ReadTimeout, requests.exceptions.ConnectionError):
            with contextlib.suppress(Exception):
                c.kill()
            out = c.logs(stdout=True, stderr=True).decode("utf-8", "replace")
            raise ContainerError(f"container command timed out after {timeout:.0f} s: "
                                 f"{command}\n{out[-3000:]}") from None
        out = c.logs(stdout=True, stderr=True).decode("utf-8", "replace")
        code = int(status.get("StatusCode", -1))
    finally:
        with contextlib.suppress(Exception):
            c.remove(force=True)
    return ContainerResult(code, out, time.monotonic() - t0, image, command)


def build_modules(moddir: str, *, warnings: bool = True, extra_args: Sequence[str] = (),
                  image: Optional[str] = None, timeout: float = 900,
                  jobs: Optional[int] = None) -> ContainerResult:
    """``make -C <headers> M=MODDIR W=1 modules`` inside the build container."""
    _, rel, _ = _headers()
    moddir = os.path.realpath(moddir)
    args = ["make", "-C", f"/usr/src/linux-headers-{rel}", f"M={moddir}",
            f"-j{jobs or os.cpu_count() or 1}"]
    if warnings:
        args.append("W=1")
    args += list(extra_args) + ["modules"]
    command = " ".join(shlex.quote(a) for a in args)
    if image is None:
        image = image_tag()
    ckey = before = None
    if buildcache.cache_dir():
        try:   # the image's id, not its tag: what the build runs is the key
            image_id = docker_client().images.get(image).id
        except Exception as e:
            raise ContainerError(f"container image {image} is missing: run scripts/setup.sh "
                                 f"(or python -m iec2kmod.container ensure): {e}") from None
        ckey = buildcache.key(moddir, ["container", image_id],
                              [a for a in args if a != f"M={moddir}" and not a.startswith("-j")])
        hit = buildcache.restore(ckey, moddir)
        if hit is not None:
            return ContainerResult(hit[0], hit[1], 0.0, image, command, cached=True)
        before = buildcache.snapshot(moddir)
    res = run_in_container(moddir, command, image=image, timeout=timeout)
    if ckey and res.ok:
        buildcache.store(ckey, moddir, before, res.output)
    return res


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m iec2kmod.container",
                                 description="iec2kmod module-build container")
    sub = ap.add_subparsers(dest="cmd", required=True)
    e = sub.add_parser("ensure", help="build the image if it is missing")
    e.add_argument("--rebuild", action="store_true")
    sub.add_parser("tag", help="print the image tag for the current recipe")
    r = sub.add_parser("run", help="run a command in the image with DIR mounted")
    r.add_argument("dir")
    r.add_argument("command", nargs=argparse.REMAINDER)
    a = ap.parse_args(argv)
    try:
        if a.cmd == "ensure":
            ensure_image(rebuild=a.rebuild, log=lambda m: print(f"[container] {m}", flush=True))
        elif a.cmd == "tag":
            print(image_tag())
        else:
            cmd = a.command[1:] if a.command[:1] == ["--"] else a.command
            if not cmd:
                ap.error("run: no command given")
            res = run_in_container(a.dir, " ".join(shlex.quote(c) for c in cmd))
            sys.stdout.write(res.output)
            return res.exit_code
    except ContainerError as err:
        print(f"error: {err}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
