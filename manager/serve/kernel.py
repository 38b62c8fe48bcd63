# SPDX-License-Identifier: MIT
"""The server's side of the netlink connection: one socket, used by one
thread at a time (a lock), called from the asyncio loop through
``asyncio.to_thread`` so a slow reply never stalls the other clients.

Reads are one VAR_GET request per <= 32 variables (the kernel copies each
request's variables under its table lock); writes are the manager's
validated path: the value checked with the rules of ``plc-manager write``
(model.check), encoded by values.encode, and one VAR_SET for every
variable of a client request (the kernel applies them together at the
next cycle boundary of each task, or refuses them all)."""

from __future__ import annotations

import asyncio
import errno
import threading
from typing import Dict, Sequence, Tuple

from .. import values
from ..netlink import Client, KernelError, Status
from .model import Model, Refused


class Kernel:
    """pyroute2's socket runs its own event loop: it is created and used
    in one worker thread of its own (never in the asyncio loop's)."""

    def __init__(self, model: Model, client: Client) -> None:
        self.model = model
        self.c = client
        self.lock = threading.Lock()
        self.requests = 0
        self.reconnects = 0
        self.connect = None     # () -> a new client (serve: ops.connect)
        self.pool = None

    @classmethod
    def open(cls, pool, loader):
        """*loader* () -> (client, model), run in *pool*'s thread."""
        c, model = pool.submit(loader).result()
        k = cls(model, c)
        k.pool = pool
        return k

    def close(self) -> None:
        def _close():
            with self.lock:
                self.c.close()
        if self.pool is not None:
            self.pool.submit(_close).result()
            self.pool.shutdown()
        else:
            _close()

    async def _run(self, fn, *args):
        if self.pool is None:
            return await asyncio.to_thread(fn, *args)
        return await asyncio.get_running_loop().run_in_executor(self.pool, fn, *args)

    # -- blocking -----------------------------------------------------
    def read_now(self, paths: Sequence[str]) -> Dict[str, object]:
        """path (as given) -> value (None: the kernel sent no value)."""
        types = [self.model.var(p) for p in paths]
        with self.lock:
            self.requests += 1
            got = self.c.var_get([t.path for t in types])
        by = {v.path.lower(): v for v in got}
        out = {}
        for p, t in zip(paths, types):
            v = by.get(t.path.lower())
            out[p] = values.decode(t, v.value) if v is not None and v.value is not None \
                else None
        return out

    def write_now(self, items: Sequence[Tuple[str, object]]) -> None:
        """Checked values (model.check / from_ua / from_registers) to the
        kernel in one VAR_SET; a refusal raises :class:`Refused`."""
        enc = []
        for p, v in items:
            t = self.model.var(p)
            v = self.model_check(t, v)
            enc.append((t.path, values.encode(t, v)))
        try:
            with self.lock:
                self.requests += 1
                self.c.var_set(enc)
        except KernelError as e:
            name = items[0][0] if len(items) == 1 else "a variable"
            if e.code == errno.EACCES:
                raise Refused("access", f"{name} is read-only") from None
            if e.code == errno.ERANGE:
                raise Refused("range", f"{name}: out of range") from None
            if e.code == errno.EBUSY:
                raise Refused("access", f"{name} is forced") from None
            if e.code == errno.EINVAL:
                raise Refused("type", f"{name}: the kernel refused the value: {e}") from None
            raise Refused("failure", f"write refused by the kernel: {e}") from None

    @staticmethod
    def model_check(t, v):
        from .model import check
        return check(t, v)

    def status_now(self) -> Status:
        """The kernel's status; when it does not answer (the configuration
        module went away: a stop, a load), a new connection is tried (a
        module loaded again registers its netlink family anew)."""
        from ..errors import PLCError
        with self.lock:
            self.requests += 1
            try:
                return self.c.status()
            except PLCError:
                if self.connect is None:
                    raise
            try:
                c = self.connect()
            except PLCError:
                raise
            try:
                self.c.close()
            except Exception:       # a socket of a family that is gone
                pass
            self.c = c
            self.reconnects += 1
            return self.c.status()

    # -- async --------------------------------------------------------
    async def read(self, paths: Sequence[str]) -> Dict[str, object]:
        return await self._run(self.read_now, list(paths))

    async def write(self, items: Sequence[Tuple[str, object]]) -> None:
        await self._run(self.write_now, list(items))

    async def status(self) -> Status:
        return await self._run(self.status_now)

