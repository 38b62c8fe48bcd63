"""Pass 'configure', located variables: the rules of directly represented
addresses (``AT %IX0.0``) over a whole configuration.

An address has a type (``check_address_type``: a bit address is BOOL, a
byte, word, double or long address an elementary type of that size, which
the pass 'declare' checks too) and a span of bits (``address_span``); it is
accessed by exactly one variable, of one resource (``check_address_rules``:
no address twice, no overlapping spans); a program type that declares
located variables has one instance; an incomplete location (``AT %I*``) is
completed by VAR_CONFIG.

``LocatedRules`` is mixed into checks.config.ConfigChecker, whose
``error``, ``addresses``, ``paths``, ``located_owner`` and ``completed`` it
uses; ``note_address``, ``note_direct`` and ``note_global_use`` record what
the rest of that pass finds."""

from __future__ import annotations

import os

from .symbols import Var
from .types import BOOL, ERROR, Elementary, FBType


class LocatedRules:
    # ------------------------------------------------ program instances
    def program_located(self, pou, inst, pc, r, src):
        """The located variables a program type declares (ed.2
        located_var_declarations) belong to its one instance: a second
        instance would give their addresses a second variable."""
        located = [v for v in pou.vars.values() if v.location and not v.location.endswith("*")]
        if not located:
            return
        owner = self.located_owner.get(pou.key)
        if owner is not None:
            v = located[0]
            more = f" and {len(located) - 1} more" if len(located) > 1 else ""
            self.error(src, pc.pos,
                       f"a second instance '{pc.name}' of program '{pou.name}', which declares "
                       f"'{v.name}' AT {v.location}{more} ({_place(v.src, v.pos)}): the first "
                       f"instance '{owner[0]}' ({owner[1]}) has that address, and one address is "
                       "accessed by exactly one variable; instantiate the program once, or "
                       f"declare '{v.name}' AT {v.location[:3].rstrip('XBWDL0123456789.')}* and "
                       "give each instance its address in VAR_CONFIG")
            return
        self.located_owner[pou.key] = (pc.name, _place(src, pc.pos))
        path = r.path(inst.name)
        for v in located:
            self.note_direct(v.location, r.name, v.src, v.pos,
                             f"'{path}.{v.name}'", var=v)
            self.paths.setdefault(v.location, f"{path}.{v.name}")

    def check_completed(self, cfg):
        """Every incomplete location (AT %I*) of a program instance, or of a
        function block instance in one, is completed by VAR_CONFIG."""
        done = self.completed
        for r in cfg.resources:
            for inst in r.programs:
                for path, v in _incomplete(inst.pou, r.path(inst.name), 0):
                    if path.upper() not in done:
                        self.error(cfg.src, inst.node.pos,
                                   f"'{path}' is declared AT {v.location} "
                                   f"({_place(v.src, v.pos)}): its location must be completed "
                                   f"in the configuration's VAR_CONFIG ({path} AT "
                                   f"{v.location[:-1]}... : {v.type.name};)")

    # -------------------------------------------------------- addresses
    def note_address(self, v: Var, resource, src):
        if v.location:
            self.note_direct(v.location, resource, src, v.pos, f"'{v.name}'", var=v)

    def note_direct(self, addr, resource, src, pos, who, var=None, typ=None):
        # [who, declaring resource, src, pos, variable, resources using it, type]
        self.addresses.setdefault(addr, []).append(
            [who, resource, src, pos, var, set(), typ if var is None else var.type])

    def note_global_use(self, g, r, src, pos):
        """A located configuration global used by a program of resource r."""
        if not g.location:
            return
        for entry in self.addresses.get(g.location, []):
            if entry[4] is g:
                entry[5].add(r.name)

    def check_address_rules(self, src):
        spans = []
        for addr, entries in self.addresses.items():
            if len(entries) > 1:
                first = entries[0]
                for e in entries[1:]:
                    self.error(e[2], e[3], f"address {addr} is already used by {first[0]} "
                                           f"({_place(first[2], first[3])}): one address is "
                                           "accessed by exactly one variable")
            for e in entries:
                resources = set(e[5])
                if e[1] is not None:
                    resources.add(e[1])
                if len(resources) > 1:
                    self.error(e[2], e[3], f"located variable {e[0]} at {addr} is used by "
                                           f"resources {', '.join(sorted(resources))}: a located "
                                           "address belongs to one resource")
            span = address_span(addr)
            if span is not None:
                spans.append((span, addr, entries[0]))
        spans.sort(key=lambda s: (s[0][0], s[0][1]))
        for (a, b) in zip(spans, spans[1:]):
            (area1, start1, n1), addr1, e1 = a
            (area2, start2, n2), addr2, e2 = b
            if area1 == area2 and start2 < start1 + n1:
                self.error(e2[2], e2[3], f"address {addr2} overlaps {addr1} ({e1[0]}, "
                                         f"{_place(e1[2], e1[3])}): one address is accessed by "
                                         "exactly one variable" + _tables_note(addr1, addr2))


SIZE_PREFIX_BITS = {"X": 1, "B": 8, "W": 16, "D": 32, "L": 64}


def address_span(addr: str):
    """(area, first bit, bit count) of a direct address, or None when it has
    more than the two levels byte.bit."""
    area = addr[1]
    rest = addr[2:]
    size = "X"
    if rest and rest[0] in SIZE_PREFIX_BITS:
        size, rest = rest[0], rest[1:]
    parts = rest.split(".")
    if size == "X":
        if len(parts) == 2:
            return area, int(parts[0]) * 8 + int(parts[1]), 1
        if len(parts) == 1:
            return area, int(parts[0]), 1
        return None
    if len(parts) != 1:
        return None
    nbytes = SIZE_PREFIX_BITS[size] // 8
    return area, int(parts[0]) * nbytes * 8, SIZE_PREFIX_BITS[size]


def check_address_type(decl_ctx, src, pos, addr, t):
    rest = addr[2:]
    size = rest[0] if rest and rest[0] in SIZE_PREFIX_BITS else "X"
    if size == "X" and rest and rest[0] != "X" and "." not in rest:
        size = "X"
    bits = SIZE_PREFIX_BITS[size]
    base = t.base if t is not ERROR else None
    if base is None or not isinstance(base, Elementary):
        decl_ctx.error(src, pos, f"located variable at {addr} must have an elementary type")
        return
    if bits == 1:
        if base is not BOOL:
            decl_ctx.error(src, pos, f"{addr} is a bit address: its variable must be BOOL, "
                                     f"not {base.name}")
    elif base.bits != bits or base.cat == "bool":
        decl_ctx.error(src, pos, f"{addr} holds {bits} bits; {base.name} has "
                                 f"{base.bits if base.cat != 'bool' else 1}")


def _size(addr: str) -> str:
    return addr[2] if len(addr) > 2 and addr[2].isalpha() else "X"


def _tables_note(addr1: str, addr2: str) -> str:
    """For two addresses of different sizes: how the areas are laid out,
    and the dialect that keeps the sizes apart."""
    if _size(addr1) == _size(addr2):
        return ""
    return (" (iec2kmod's process image is one array of bytes per area, %QW0 holding "
            "%QX0.0 to %QX1.7; OpenPLC keeps each size in a table of its own, where "
            f"{addr1} and {addr2} are two things: give one of them another address)")


def _place(src, pos):
    """file:line:col of a declaration (the file's name: the same message
    wherever the project lies)."""
    if src is None or pos is None:
        return "?"
    line, col = src.linecol(pos)
    return f"{os.path.basename(src.path)}:{line}:{col}"


def _incomplete(pou, path, depth):
    """(path, Var) of every incomplete location in an instance of pou: its
    own and those of the function block instances it holds."""
    if pou is None or depth > 32:
        return
    for v in pou.vars.values():
        if v.location and v.location.endswith("*"):
            yield f"{path}.{v.name}", v
        elif isinstance(v.type, FBType) and not v.type.pou.standard and \
                v.section in ("VAR", "VAR_INPUT", "VAR_OUTPUT"):
            yield from _incomplete(v.type.pou, f"{path}.{v.name}", depth + 1)
