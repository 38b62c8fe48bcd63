#!/usr/bin/env python3
"""Experiment (issue 11, item 2): change detection where values are written
(dirty flags set by the writer) against the comparison before every call
that ``--selective`` generates, measured on the interlock program of
benchmarks/selective.py.  Not a product path: it patches the C that
``sim --selective`` generates for that one program and prints what the
other design would cost, so the choice is measured rather than estimated.

The writer-side variant, as a full implementation would have it:

* every block instance gets a dirty byte in its selective state;
* a map, built once, from each input variable to the dirty bytes of the
  blocks whose argument set holds it: the Interlock device reading it
  through its VAR_IN_OUT, its Station, the Machine program (estop_chain
  and line_enable: every block);
* the writer marks them: the simulator's input events are queued and the
  task drains the queue first thing in its cycle (so the marking is
  counted in the task's instructions, about ten per write);
* a block's check tests its dirty byte (and, as now, whether its
  VAR_IN_OUT binding moved) instead of comparing its argument set with
  the copy taken at its last evaluation, and its evaluation clears the
  byte instead of taking that copy.  Everything else (settling, confirm
  runs, busy periods, epochs, the statistics) is the generated code as is.

The program's own stores never reach a device's or a station's argument
set here (the blocks only read their VAR_IN_OUT and the two externals), so
the map of input events is the whole writer side for this program; a
general implementation must also mark at ST stores, stores through
VAR_IN_OUT pointers, the manager's set/force and other tasks' copy-out.
The traces of every global are checked identical to the plain build's.

    python3 benchmarks/selective_writer_side.py [--cycles 400] [--rates 0,1,10,100] [--smoke]

Prints plain, selective as generated (comparison) and writer-side flags,
callgrind instructions per scan inside the task (valgrind needed)."""

from __future__ import annotations

import argparse
import importlib.util
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from iec2kmod import sim  # noqa: E402
from iec2kmod.parse import frontend  # noqa: E402
from iec2kmod.compilation import Compilation  # noqa: E402

_spec = importlib.util.spec_from_file_location("selbench", ROOT / "benchmarks" / "selective.py")
selbench = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(selbench)

# the shadows a writer-side flag replaces, per generated file: the machine
# keeps e1..e3 (its own outputs, compared again when it settles)
REPLACED = {
    "pou_interlock.c": r"d_io|e0|e1",
    "pou_station.c": r"d_io|e0|e1",
    "pou_machine.c": r"e0|e4|e5",
}


def _patch_pou(text: str, shadows: str) -> str:
    term = re.compile(r"iec_sel_ne\([^;|]*?&self->sel\.(?:%s), sizeof\(self->sel\.(?:%s)\)\)"
                      % (shadows, shadows))
    m = re.search(r"bool sel_changed = (.*?);\n", text, re.S)
    terms = [t.strip() for t in m.group(1).split("||")]
    kept = [t for t in terms if not term.fullmatch(t)]
    assert len(kept) < len(terms), "no shadow replaced"
    new = " ||\n\t\t".join(kept + ["self->sel.dirty"])
    text = text[:m.start(1)] + new + text[m.end(1):]
    copy = re.compile(r"\tiec_memcpy\(&self->sel\.(?:%s), [^;]*;\n" % shadows)
    assert copy.search(text), "no shadow copy"
    text = copy.sub("", text)
    return text.replace("\tself->sel.epoch = ctx->sel_epoch;\n",
                        "\tself->sel.epoch = ctx->sel_epoch;\n\tself->sel.dirty = 0;\n", 1)


def _patch_types(text: str) -> str:
    for pou in ("fb_interlock", "fb_station", "prog_machine"):
        head = f"struct {pou}_sel {{\n"
        assert head in text
        text = text.replace(head, head + "\tiec_u8 dirty;\t\t/* writer-side flag */\n", 1)
    return text


def _writer_map(project_c: str, stations: int, devices: int) -> str:
    """C: the map from sim_vars indexes to dirty bytes, the queue and its
    drain, called at the start of task_0."""
    names = re.findall(r'^\t\{ "([^"]+)", ', project_c.split("sim_vars[] = {", 1)[1], re.M)
    dev, sta = [], []
    for name in names:
        m = re.match(r"st\[(\d+)\]\.dev\[(\d+)\]\.", name)
        if m:
            s, d = int(m.group(1)), int(m.group(2))
            dev.append(f"&inst_main_machine.v_s{s}.v_d{d}.sel.dirty")
            sta.append(f"&inst_main_machine.v_s{s}.sel.dirty")
        elif name in ("estop_chain", "line_enable"):
            dev.append("WD_ALL")
            sta.append("WD_ALL")
        else:
            dev.append("NULL")
            sta.append("NULL")
    everyone = [f"&inst_main_machine.v_s{s}.v_d{d}.sel.dirty"
                for s in range(1, stations + 1) for d in range(1, devices + 1)]
    everyone += [f"&inst_main_machine.v_s{s}.sel.dirty" for s in range(1, stations + 1)]
    return f"""
/* writer-side dirty flags (benchmarks/selective_writer_side.py) */
static iec_u8 wd_all_marker;
#define WD_ALL (&wd_all_marker)
static iec_u8 *const wd_dev[] = {{ {", ".join(dev)} }};
static iec_u8 *const wd_sta[] = {{ {", ".join(sta)} }};
static iec_u8 *const wd_everyone[] = {{ {", ".join(everyone)} }};
static int wd_queue[8192];
static unsigned int wd_len;

void sim_wd_note(int var);
void sim_wd_note(int var)
{{
	if (wd_len == sizeof(wd_queue) / sizeof(wd_queue[0])) {{
		fprintf(stderr, "writer-side queue full\\n");
		exit(70);
	}}
	wd_queue[wd_len++] = var;
}}

static void wd_drain(void)
{{
	unsigned int i, k;

	for (i = 0; i < wd_len; i++) {{
		iec_u8 *d = wd_dev[wd_queue[i]];

		inst_main_machine.sel.dirty = 1;
		if (d == WD_ALL) {{
			for (k = 0; k < sizeof(wd_everyone) / sizeof(wd_everyone[0]); k++)
				*wd_everyone[k] = 1;
		}} else if (d) {{
			*d = 1;
			*wd_sta[wd_queue[i]] = 1;
		}}
	}}
	wd_len = 0;
}}
"""


def build_writer_side(sel_exe: Path, work: Path, stations=10, devices=10) -> Path:
    src = sel_exe.parent
    out = work / "writer_side"
    shutil.rmtree(out, ignore_errors=True)
    shutil.copytree(src, out)
    for name, shadows in REPLACED.items():
        p = out / name
        p.write_text(_patch_pou(p.read_text(), shadows))
    t = out / "iec_press_types.h"
    t.write_text(_patch_types(t.read_text()))
    pc = out / "sim_project.c"
    text = pc.read_text()
    text = text.replace('#include "sim.h"\n', '#include "sim.h"\n#include <stdio.h>\n#include <stdlib.h>\n', 1)
    anchor = "/* the task's frame area (iec_fault.h) */"
    assert anchor in text
    text = text.replace(anchor, _writer_map(text, stations, devices) + "\n" + anchor, 1)
    head = "static void task_0(struct iec_ctx *ctx)\n{\n"
    assert head in text
    text = text.replace(head, head + "\twd_drain();\n", 1)
    pc.write_text(text)
    main_c = (sim.sim_dir() / "sim_main.c").read_text()
    hook = "\tif (sim_sel_owned && sim_sel_owned[ev->var])\n\t\tsim_sel_epoch++;\n"
    assert hook in main_c
    main_c = main_c.replace(hook, hook + "\tsim_wd_note(ev->var);\n", 1)
    main_c = main_c.replace("static void apply(const struct event *ev)",
                            "void sim_wd_note(int var);\n\nstatic void apply(const struct event *ev)", 1)
    (out / "sim_main.c").write_text(main_c)
    flags = [f if f != "-O1" else "-O2" for f in sim.CFLAGS] + selbench.EXTRA_CFLAGS
    rt = [o for o in sim.runtime_objects(work / "build") if o.stem != "sim_main"]
    exe = out / "sim"
    cc = shutil.which("gcc")
    cmd = [cc, *flags, "-I", str(out), "-I", str(sim.runtime_dir()), "-I", str(sim.sim_dir()),
           str(out / "sim_project.c"), str(out / "sim_main.c"), *map(str, rt), "-o", str(exe), "-lm"]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        raise SystemExit(f"the writer-side variant did not compile:\n{p.stderr[:3000]}")
    return exe


def _globals_trace(exe: Path, events: Path, end: int, nvars: int) -> list:
    """Every change of every variable, and the faults, of one run."""
    watch = [str(i) for i in range(nvars)]
    p = subprocess.run([str(exe), str(end), str(events), *watch], capture_output=True, text=True)
    if p.returncode != 0:
        raise SystemExit(f"{exe} failed: {p.stderr[-2000:]}")
    return [ln for ln in p.stdout.splitlines() if ln.startswith(("v ", "f "))]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cycles", type=int, default=400)
    ap.add_argument("--rates", default="0,1,10,100")
    ap.add_argument("--seed", type=int, default=11)
    ap.add_argument("--keep", metavar="DIR")
    ap.add_argument("--smoke", action="store_true",
                    help="a few seconds' run at a small size (CI: tests/benchmarks): 30 cycles "
                         "at 0 and 100 %% of a small interlock program")
    a = ap.parse_args(argv)
    if a.smoke:
        a.cycles, a.rates = 30, "0,100"
    if shutil.which("valgrind") is None:
        raise SystemExit("valgrind not found: apt-get install valgrind (scripts/setup.sh)")
    work = Path(a.keep) if a.keep else Path(tempfile.mkdtemp(prefix="selws-"))
    work.mkdir(parents=True, exist_ok=True)
    size = selbench.SMOKE_SIZES["interlock"] if a.smoke else {"stations": 10, "devices": 10}
    text, inputs, start = selbench.interlock(**size)
    (work / "interlock.st").write_text(text)
    res = frontend.run([str(work / "interlock.st")], use_cache=False)
    if not res.ok:
        raise SystemExit("\n".join(d.format() for d in res.diags.sorted()))
    project = res.project
    plain, sel = Compilation(project), Compilation(project, "all")
    plan = plain.plan
    plain_exe, _ = selbench._build(plain, work)
    sel_exe, _ = selbench._build(sel, work)
    ws_exe = build_writer_side(sel_exe, work, **size)
    nvars = len(re.findall(r'^\t\{ "', (sel_exe.parent / "sim_project.c").read_text()
                           .split("sim_vars[] = {", 1)[1].split("};", 1)[0], re.M))
    print(f"interlock, {a.cycles} cycles, callgrind Ir per scan inside the task", flush=True)
    print(f"{'change %':>8} {'plain':>9} {'compare':>9} {'writer':>9} "
          f"{'plain/compare':>14} {'plain/writer':>13}", flush=True)
    for rate in (float(r) for r in a.rates.split(",")):
        tp = work / f"trace_{rate:g}.csv"
        tp.write_text(selbench.trace(inputs, start, rate, a.cycles, a.seed))
        ip, _ = selbench.measure(project, plain_exe, plan, tp, a.cycles, work)
        ev = work / "events.txt"           # written by measure()
        end = (a.cycles - 1) * selbench.INTERVAL_MS * 1_000_000
        ref = _globals_trace(plain_exe, ev, end, nvars)
        assert rate == 0 or len(ref) > nvars, "the reference trace shows no change"
        if (_globals_trace(ws_exe, ev, end, nvars) != ref
                or _globals_trace(sel_exe, ev, end, nvars) != ref):
            raise SystemExit(f"at {rate:g} %: a variant's trace of the globals differs from plain")
        ic, _ = selbench.measure(project, sel_exe, plan, tp, a.cycles, work)
        iw, _ = selbench.measure(project, ws_exe, plan, tp, a.cycles, work)
        print(f"{rate:8g} {ip:9.1f} {ic:9.1f} {iw:9.1f} {ip / ic:14.2f} {ip / iw:13.2f}",
              flush=True)
    if not a.keep:
        shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
