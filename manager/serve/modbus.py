# SPDX-License-Identifier: MIT
"""Modbus TCP server (pymodbus) on the model's Modbus map (model.py has
the mapping table).

Requests: FC 1, 2, 3, 4 (read), 5, 6, 15, 16 (write), 22 (mask write),
23 (write then read).  Every read asks the kernel for the variables it
covers in one request (one snapshot per request); a write goes through
the manager's validated write path, all the variables of one request in
one VAR_SET.  Answers:

* 02 ILLEGAL DATA ADDRESS: the range holds no mapped variable (a read;
  holes between mapped variables read 0, as in OpenPLC), or a write
  touches an address where nothing is mapped;
* 03 ILLEGAL DATA VALUE: the value does not fit the variable (range,
  subrange, enumeration, a BOOL register other than 0/1, a REAL that is
  not finite), or the kernel refused it as out of range;
* 04 SERVER DEVICE FAILURE: the variable may not be written (read-only:
  an output the program drives, a READ_ONLY access path, a forced
  variable), or the kernel is not reachable (configuration stopped).
"""

from __future__ import annotations

import logging
from typing import Dict, List, Sequence

from pymodbus.constants import ExcCodes
from pymodbus.datastore import ModbusServerContext

from ..errors import PLCError
from .kernel import Kernel
from .model import Cell, ModbusMap, Refused, from_registers, registers_of, to_registers

log = logging.getLogger("plc_manager.serve.modbus")

TABLE = {1: "co", 5: "co", 15: "co", 2: "di", 4: "ir",
         3: "hr", 6: "hr", 16: "hr", 22: "hr", 23: "hr"}


class PlcContext(ModbusServerContext):
    """The datastore of every unit id: the kernel, through the map."""

    def __init__(self, kernel: Kernel, mmap: ModbusMap) -> None:
        # not super().__init__: pymodbus would build a simulated device
        self._devices = {}
        self.simdevices = []
        self.old_simulator = True      # pymodbus then calls async_getValues/async_setValues
        self.kernel = kernel
        self.map = mmap
        self.requests = 0
        self.refused = 0

    def device_ids(self):
        return [0]

    def _cells(self, fc: int, address: int, count: int):
        table = self.map.table(TABLE.get(fc, "hr"))
        return [table.get(a) for a in range(address, address + count)]

    async def async_getValues(self, device_id: int, func_code: int, address: int,
                              count: int = 1):
        self.requests += 1
        if func_code not in TABLE:
            return ExcCodes.ILLEGAL_FUNCTION
        cells = self._cells(func_code, address, count)
        if count < 1 or not any(cells):
            return ExcCodes.ILLEGAL_ADDRESS
        paths = sorted({c.path for c in cells if c is not None})
        try:
            vals = await self.kernel.read(paths)
        except PLCError as e:
            log.warning("modbus read: %s", e)
            return ExcCodes.DEVICE_FAILURE
        bits = TABLE[func_code] in ("co", "di")
        out: List[int] = []
        regs: Dict[str, List[int]] = {}
        for c in cells:
            if c is None or vals.get(c.path) is None:
                out.append(False if bits else 0)
                continue
            t = self.kernel.model.var(c.path)
            if bits:
                out.append(bool(vals[c.path]))
                continue
            if c.path not in regs:
                regs[c.path] = to_registers(t, vals[c.path])
            out.append(regs[c.path][c.word])
        return out

    async def async_setValues(self, device_id: int, func_code: int, address: int,
                              values: Sequence):
        self.requests += 1
        if func_code not in TABLE or TABLE[func_code] not in ("co", "hr"):
            return ExcCodes.ILLEGAL_FUNCTION
        cells = self._cells(func_code, address, len(values))
        if not values or any(c is None for c in cells):
            self.refused += 1
            return ExcCodes.ILLEGAL_ADDRESS
        if any(not c.writable for c in cells):
            self.refused += 1
            return ExcCodes.DEVICE_FAILURE
        # the registers of each variable; a variable written in part keeps
        # its other registers (read first)
        words: Dict[str, Dict[int, int]] = {}
        for c, v in zip(cells, values):
            words.setdefault(c.path, {})[c.word] = int(v)
        partial = [p for p, w in words.items()
                   if len(w) < registers_of(self.kernel.model.var(p))]
        try:
            current = await self.kernel.read(partial) if partial else {}
            items = []
            for p, w in words.items():
                t = self.kernel.model.var(p)
                if TABLE[func_code] == "co":
                    items.append((p, bool(w[0])))
                    continue
                regs = to_registers(t, current[p]) if p in current else [0] * registers_of(t)
                for i, r in w.items():
                    regs[i] = r
                items.append((p, from_registers(t, regs)))
            await self.kernel.write(items)
        except Refused as e:
            self.refused += 1
            log.info("modbus write refused: %s", e)
            return ExcCodes.DEVICE_FAILURE if e.why in ("access", "failure") \
                else ExcCodes.ILLEGAL_VALUE
        except PLCError as e:
            self.refused += 1
            log.warning("modbus write: %s", e)
            return ExcCodes.DEVICE_FAILURE
        return None


async def start(kernel: Kernel, mmap: ModbusMap, host: str, port: int):
    """A started pymodbus TCP server (asyncio); stop it with
    ``await server.shutdown()``."""
    from pymodbus.server import ModbusTcpServer
    ctx = PlcContext(kernel, mmap)
    server = ModbusTcpServer(ctx, address=(host, port))
    try:
        await server.serve_forever(background=True)
    except (RuntimeError, OSError) as e:
        raise PLCError(f"modbus {host}:{port}: cannot listen ({e}): the port is taken, "
                       f"or below 1024 without CAP_NET_BIND_SERVICE") from None
    server.plc_context = ctx
    return server


__all__ = ["PlcContext", "start", "Cell"]
