"""The soundness campaign of `iec2kmod verify` (issue 22): random projects
restricted to small domains, with planted bugs only deep runs reach, each
verified by the z3 engine and by the explicit-state referee
(iec2kmod.verify.explicit); a disagreement is a failure.

A project (generate(seed)): two or three BOOL inputs at %IX addresses, one
or two periodic tasks (10, 20 or 30 ms), two or three programs, each one
pattern with a planted bug --

    latch   arming latched through a TON's output (the PRESS of issue 22)
    count   a CTU on an input's edges, reset through its own output
    fault   a run of N cycles with an input TRUE reaches a division by zero
    pulse   a TP, its output read with the inputs
    sr      an SR set by a TON's output, reset by an input
    phase   an enumeration state machine leaving RUN through a TON

-- timers of 10 to 40 periods of their task, programs of different tasks
connected through the outputs of one another (a %QX global read as an
input), properties over inputs and outputs together, and in about one
project in three an assumption over the connected inputs (in one in ten an
assumption over an output, which can block every run: vacuity).

Agreement, per check (the implicit "no runtime error" included):

    explicit            z3 must be
    violated at K       violated at K; or holds up to N (undecided) with N < K
    proved              proved, or holds up to N / undecided
    vacuous (runs <= L) vacuous at the same L, or holds up to N <= L
    too large (depth D) anything but violated at K <= D

"""

from __future__ import annotations

import contextlib
import io
import random
import re
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

PERIODS = (10, 20, 30)


@dataclass
class Project:
    seed: int
    text: str
    props: list
    assumes: list
    patterns: list = field(default_factory=list)


def _prog(kind, name, rnd, period):
    """(POU text, VAR_OUTPUT n present)."""
    n = rnd.randint(10, 40)
    pt = f"T#{n * period}ms"
    if kind == "latch":
        body = f"""  arm := (a OR t.Q) AND b;
  t(IN := arm, PT := {pt});
  q := t.Q AND arm;"""
        decl = "arm : BOOL; t : TON;"
    elif kind == "count":
        k = rnd.randint(3, 9)
        body = f"""  c(CU := a, R := c.Q OR NOT b, PV := {k});
  q := c.Q;
  n := c.CV;"""
        decl = "c : CTU;"
    elif kind == "fault":
        k = rnd.randint(5, 20)
        body = f"""  IF a THEN m := m + 1; ELSE m := 0; END_IF;
  IF m > {k} THEN m := 0; END_IF;
  IF m = {k} AND b THEN d := 100 / (m - {k}); END_IF;
  q := m > {k - 2};
  n := m;"""
        decl = "m : INT; d : INT;"
    elif kind == "pulse":
        body = f"""  t(IN := a, PT := {pt});
  q := t.Q OR (b AND NOT a);"""
        decl = "t : TP;"
    elif kind == "sr":
        body = f"""  t(IN := a AND NOT b, PT := {pt});
  l(S1 := t.Q, R := b);
  q := l.Q1;"""
        decl = "t : TON; l : SR;"
    else:   # phase
        body = f"""  CASE ph OF
    IDLE: IF a THEN ph := RUN; END_IF;
    RUN: IF NOT b THEN ph := IDLE; END_IF;
    DONE: IF NOT a THEN ph := IDLE; END_IF;
  END_CASE;
  t(IN := ph = RUN, PT := {pt});
  IF t.Q THEN ph := DONE; END_IF;
  q := ph = DONE;
  n := ph = RUN;"""
        decl = "ph : Ph; t : TON;"
    n_type = {"count": "INT", "fault": "INT", "phase": "BOOL"}.get(kind)
    outs = "q : BOOL;" + (f" n : {n_type};" if n_type else "")
    text = f"""PROGRAM {name}
  VAR_INPUT a : BOOL; b : BOOL; END_VAR
  VAR_OUTPUT {outs} END_VAR
  VAR {decl} END_VAR
{body}
END_PROGRAM
"""
    return text, n_type


def generate(seed) -> Project:
    rnd = random.Random(seed)
    n_in = rnd.randint(2, 3)
    ins = [f"I{i}" for i in range(n_in)]
    n_tasks = rnd.choice((1, 2, 2))
    periods = sorted(rnd.sample(PERIODS, n_tasks))
    n_prog = rnd.choice((2, 2, 3))
    pous, globs, insts, props, assumes, kinds = [], [], [], [], [], []
    outs = []          # (global name, n global or None, n type)
    uses_phase = False
    for g, name in enumerate(ins):
        globs.append(f"{name} AT %IX0.{g} : BOOL;")
    for p in range(n_prog):
        kind = rnd.choice(("latch", "count", "fault", "pulse", "sr", "phase"))
        kinds.append(kind)
        uses_phase |= kind == "phase"
        task = rnd.randrange(n_tasks)
        text, n_type = _prog(kind, f"Prog{p}", rnd, periods[task])
        pous.append(text)
        q = f"Q{p}"
        globs.append(f"{q} AT %QX0.{p} : BOOL;")
        nglob = None
        if n_type:
            nglob = f"N{p}"
            globs.append(f"{nglob} : {n_type};")
        # inputs: an address, or the output of an earlier program (another task's maybe)
        srcs = list(ins) + [o for o, _, _ in outs]
        a = rnd.choice(srcs)
        b = rnd.choice([s for s in ins if s != a] or ins)
        conn = f"a := {a}, b := {b}, q => {q}" + (f", n => {nglob}" if nglob else "")
        insts.append(f"    PROGRAM P{p} WITH T{task} : Prog{p} ({conn});")
        outs.append((q, nglob, n_type))
    tasks = [f"    TASK T{t} (INTERVAL := T#{periods[t]}ms, PRIORITY := {t + 1});"
             for t in range(n_tasks)]
    types = "TYPE Ph : (IDLE, RUN, DONE); END_TYPE\n" if uses_phase else ""
    text = types + "\n".join(pous) + "CONFIGURATION Cell\n  VAR_GLOBAL\n" + \
        "\n".join(f"    {g}" for g in globs) + "\n  END_VAR\n  RESOURCE Plc ON CPU0\n" + \
        "\n".join(tasks) + "\n" + "\n".join(insts) + "\n  END_RESOURCE\nEND_CONFIGURATION\n"
    # properties over inputs and outputs together
    qs = [o[0] for o in outs]
    for _ in range(rnd.randint(2, 3)):
        q = rnd.choice(qs)
        x = rnd.choice(ins)
        form = rnd.randrange(6)
        if form == 0:
            props.append(f"NOT ({q} AND NOT {x})")
        elif form == 1:
            props.append(f"NOT {q}")
        elif form == 2:
            props.append(f"NOT ({q} AND {rnd.choice([o for o in qs if o != q] or qs)})")
        elif form == 3:
            props.append(f"{q} OR NOT {x} OR {rnd.choice(ins)}")
        elif form == 4 and any(o[1] and o[2] == "INT" for o in outs):
            n = rnd.choice([o[1] for o in outs if o[1] and o[2] == "INT"])
            props.append(f"{n} < {rnd.randint(3, 12)}")
        else:
            props.append(f"NOT ({q} AND {x} AND NOT {rnd.choice(ins)})")
    r = rnd.random()
    if r < 0.3 and len(ins) >= 2:
        x, y = rnd.sample(ins, 2)
        assumes.append(rnd.choice([f"NOT ({x} AND {y})", f"{x} OR {y}", f"{x} OR NOT {y}"]))
    elif r < 0.4:
        assumes.append(f"NOT {rnd.choice(qs)}")
    return Project(seed, text, props, assumes, kinds)


# ------------------------------------------------------------ the engines
def _front(path):
    from iec2kmod.cli import front_end
    with contextlib.redirect_stderr(io.StringIO()) as err:
        project = front_end([str(path)])
    if project is None:
        raise RuntimeError(f"front end: {err.getvalue().strip()}")
    return project


def z3_verdicts(path, props, assumes, depth, timeout_ms, project=None):
    """{name: (status, cycle)} of the z3 engine; status proved / bounded /
    violated / vacuous / unknown (cycle: K, N, the longest run)."""
    from iec2kmod.diagnostics import Diagnostics
    from iec2kmod.verify import verify
    out = verify(project or _front(path), props, assumes, depth=depth, diags=Diagnostics(),
                 timeout_ms=timeout_ms)
    if out is None:
        raise RuntimeError("z3 engine: source errors")
    return {r.name: (r.status, r.cycle) for r in out.results}


def explicit_verdicts(path, props, assumes, max_states, max_inputs=4096, project=None):
    from iec2kmod.diagnostics import Diagnostics
    from iec2kmod.verify.explicit import explore
    out = explore(project or _front(path), props, assumes, diags=Diagnostics(), max_states=max_states,
                  max_inputs=max_inputs)
    if out is None:
        raise RuntimeError("explicit engine: source errors")
    return {r.name: (r.status, r.depth if r.status == "too_large" else r.cycle)
            for r in out.results}, out.states


def disagreement(z, x):
    """None when the z3 verdict z agrees with the explicit verdict x (both
    (status, cycle)); else why not."""
    zs, zk = z
    xs, xk = x
    undecided = zs in ("bounded", "unknown")
    if xs == "violated":
        if zs == "violated" and zk == xk:
            return None
        if undecided and zk < xk:
            return None
        return f"z3 {zs} {zk}, explicit violated at {xk}"
    if xs == "proved":
        if zs == "proved" or undecided:
            return None
        return f"z3 {zs} {zk}, explicit proved"
    if xs == "vacuous":
        if zs == "vacuous" and zk == xk:
            return None
        if undecided and zk <= xk:
            return None
        return f"z3 {zs} {zk}, explicit vacuous (no run longer than {xk})"
    if xs == "too_large":
        if zs == "violated" and zk <= xk:
            return f"z3 violated at {zk}, explicit too large but found no violation in " \
                   f"every run of {xk} cycles"
        return None
    return f"explicit status {xs}"


def check_project(seed, depth=45, timeout_ms=20000, max_states=20000, workdir=None):
    """A dict: seed, verdicts of both engines, disagreements, seconds."""
    proj = generate(seed)
    wd = Path(workdir or tempfile.mkdtemp(prefix="soundgen-"))
    path = wd / f"s{seed}.st"
    path.write_text(proj.text)
    r = {"seed": seed, "file": str(path), "props": proj.props, "assumes": proj.assumes,
         "patterns": proj.patterns, "problems": []}
    t0 = time.perf_counter()
    project = _front(path)       # one front end for both (neither changes the checked AST)
    x, states = explicit_verdicts(path, proj.props, proj.assumes, max_states, project=project)
    r["explicit_s"] = time.perf_counter() - t0
    r["states"] = states
    t0 = time.perf_counter()
    z = z3_verdicts(path, proj.props, proj.assumes, depth, timeout_ms, project=project)
    r["z3_s"] = time.perf_counter() - t0
    r["explicit"], r["z3"] = x, z
    for name, xv in x.items():
        zv = z.get(name)
        if zv is None:
            r["problems"].append(f"{name}: no z3 verdict")
            continue
        why = disagreement(zv, xv)
        if why:
            text = "" if name == "no runtime error" else \
                " (" + proj.props[int(name.split()[-1]) - 1] + ")"
            r["problems"].append(f"{name}{text}: {why}")
    return r


def summary(results):
    import collections
    c = collections.Counter()
    for r in results:
        for s, _ in r["explicit"].values():
            c["explicit " + s] += 1
        for s, _ in r["z3"].values():
            c["z3 " + s] += 1
    return ", ".join(f"{k} {v}" for k, v in sorted(c.items()))


def _main_one(args):
    seed, depth, timeout_ms, max_states, workdir = args
    try:
        return check_project(seed, depth, timeout_ms, max_states, workdir)
    except Exception as exc:       # reported as a failure of the campaign
        import traceback
        return {"seed": seed, "problems": [f"exception: {exc!r}\n{traceback.format_exc()}"],
                "explicit": {}, "z3": {}, "states": 0, "explicit_s": 0, "z3_s": 0}


def campaign(seeds, depth=45, timeout_ms=20000, max_states=20000, jobs=2, log=None):
    """Runs every project (jobs worker processes); [result dict]."""
    import multiprocessing as mp
    wd = tempfile.mkdtemp(prefix="soundgen-")
    args = [(s, depth, timeout_ms, max_states, wd) for s in seeds]
    out = []
    if jobs <= 1:
        it = map(_main_one, args)
        pool = None
    else:
        pool = mp.get_context("fork").Pool(jobs)
        it = pool.imap(_main_one, args)
    try:
        for r in it:
            out.append(r)
            if log:
                log(r)
    finally:
        if pool is not None:
            pool.close()
            pool.join()
    return out


def minimal_program(text):
    """The project text with comments stripped (for regression files)."""
    return re.sub(r"\n\s*\n", "\n", text)
