# SPDX-License-Identifier: MIT
"""What both verify engines refuse: the standard FBs that read the date and
time of day.  RTC's CDT is the wall clock at the cycle's release in the
kernel; neither the z3 encoding nor the explicit exploration has a model of
it (the simulator's clock from DT#1970-01-01 is a test convention, not the
plant's), so a project holding one is refused with the variable named."""

from __future__ import annotations

from ..checks.types import ArrayT, FBType, StructT, concrete

# Standard FBs that read the date and time of day (RTC): their outputs are
# the wall clock in the kernel, which no model here represents.
CLOCK_FBS = {"RTC"}


def clock_user(project, who="verify"):
    """(src, pos, message) of the first variable whose type holds a clock FB
    (RTC, in an array or a structure too), or None: verify refuses them."""
    def holds(t, seen):
        t = concrete(t)
        if id(t) in seen:
            return None
        seen.add(id(t))
        if isinstance(t, FBType):
            if t.pou.standard and t.name.upper() in CLOCK_FBS:
                return t.name.upper()
            if not t.pou.standard:
                for v in t.pou.vars.values():
                    if (n := holds(v.type, seen)) is not None:
                        return n
            return None
        if isinstance(t, ArrayT):
            return holds(t.elem, seen)
        if isinstance(t, StructT):
            for _, mt, _ in t.fields.values():
                if (n := holds(mt, seen)) is not None:
                    return n
        return None

    scopes = [p.vars.values() for p in project.pous.values()]
    for cfg in project.configurations:
        scopes.append(cfg.globals.values())
        scopes += [r.globals.values() for r in cfg.resources]
    for scope in scopes:
        for v in scope:
            if (n := holds(v.type, set())) is not None:
                return v.src, v.pos, (f"{who}: '{v.name}' holds an {n} instance (it reads "
                                      "the real-time clock, the wall clock in the kernel): "
                                      f"{who} does not model the date and time of day")
    return None
