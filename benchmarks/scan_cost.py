#!/usr/bin/env python3
"""Benchmark: instructions per scan cycle, generated C versus hand-written C.

Three programs (benchmarks/scan_cost/):

    interlock   boolean interlock of a hydraulic press (BOOL logic, edges, SR)
    pid         arithmetic-heavy PID controller on REAL
    recipe      string- and array-heavy recipe handler

each also written by hand in C as a careful C programmer would, with the
same semantics (wrap-around INT arithmetic, checked array indexes,
truncating bounded strings, NaN-propagating LIMIT).  Both versions run the
same N cycles on the same deterministic inputs; a checksum of the outputs
after every cycle must agree, so the two compute the same thing.

Only the body is measured: valgrind's callgrind with
--toggle-collect=<body function> counts the instructions executed in the
body and everything it calls (runtime helpers included), not the driver
loop that sets the inputs.  The generated program body is compiled as in a
program-type module: one translation unit, the program body not inlined
into its caller (the kernel calls it through the GFT), nested blocks free
to inline; runtime objects linked separately; -O2 for everything.

    python benchmarks/scan_cost.py [--cycles 20000] [--keep DIR] [--smoke]

Prints: program, IEC instructions/cycle, hand-written instructions/cycle,
ratio (target <= 1.3).  Exit status 1 if a ratio is above --target.

Results (gcc 12 -O2, x86-64, 20000 cycles), emitter before and after the
optimisations this benchmark prompted (string fast paths, && for pure BOOL
operands, SR/RS/R_TRIG/F_TRIG written out, FOR loops with constant bounds:
unchecked in-range indexes and one loop-budget charge, no fault check after
a division by a non-zero constant):

    program      IEC before   IEC after   hand   ratio before  ratio after
    interlock       160.9       104.4     82.1       1.96          1.27
    pid             128.9       129.9    130.7       0.99          0.99
    recipe         1702.2       350.5    394.7       4.31          0.89
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
HERE = Path(__file__).resolve().parent / "scan_cost"

from iec2kmod.parse import frontend  # noqa: E402
from iec2kmod.codegen import generate  # noqa: E402
from iec2kmod.codegen.pou import frame_need  # noqa: E402
from iec2kmod.resources import templates_root  # noqa: E402

TEMPLATES = templates_root()

RUNTIME = TEMPLATES / "runtime"
RUNTIME_SOURCES = ("iec_string.c", "iec_std_fb.c", "iec_math.c", "iec_real.c")
CFLAGS = ["-std=gnu11", "-O2", "-fno-strict-aliasing", "-Wall", "-Wextra",
          "-Wno-unused-function", "-Wno-unused-parameter"]
CYCLE_NS = 10_000_000

# Inputs as C statements per cycle: F(x) is the field of input x, k the
# cycle number, r a fresh 32-bit pseudo-random number (xorshift).
BENCHES = {
    "interlock": {
        "inputs": """
            F(estop_ok) = (r % 97) != 0;
            F(guard_closed) = (r >> 3) % 41 != 0;
            F(curtain_clear) = (r >> 5) % 13 != 0;
            F(two_hand_l) = (k / 7) % 3 != 0;
            F(two_hand_r) = (k / 5) % 4 != 0;
            F(pump_feedback) = (r >> 7) % 53 != 0;
            F(pressure_ok) = (r >> 9) % 61 != 0;
            F(oil_temp_ok) = (r >> 11) % 211 != 0;
            F(top_limit) = (k % 40) < 3;
            F(bottom_limit) = (k % 40) > 35;
            F(mode_auto) = (k / 500) % 2 == 0;
            F(mode_setup) = (k / 500) % 2 == 1;
            F(ack) = (k % 150) < 2;
            F(start_pb) = (k % 90) == 1;
            F(stop_pb) = (k % 333) == 0;""",
        "outputs": ["pump_on", "valve_down", "valve_up", "lamp_ready", "lamp_fault", "horn",
                    "fault_code"],
    },
    "pid": {
        "inputs": """
            F(setpoint) = (float)(20 + (k / 400) % 5 * 15);
            F(measured) = (float)(30.0 + 25.0 * ((int)(r % 1000) - 500) / 500.0);
            F(manual) = (k / 1000) % 7 == 3;
            F(manual_out) = (float)((k / 100) % 11 * 9.5);""",
        "outputs": ["out", "error", "saturated"],
    },
    "recipe": {
        "inputs": """
            if (k % 25 == 0) {
                static const char *const req[] = { "BASE", "PRIMER-A", "PRIMER-B",
                    "GLOSS", "MATT", "SEALER", "THINNER", "CLEAN", "UNKNOWN", "GLOSSY" };
                SET_STR(F(request), req[(r >> 4) % 10]);
            }
            F(step_done) = (k % 6) < 3;
            F(scale) = (short)(5 + (k / 25) % 12);""",
        "outputs": ["active_name", "status", "dose", "total", "found", "step"],
        "strings": ["active_name", "status"],
    },
}

DRIVER = r"""
#include <stdio.h>
#include <stdint.h>
#include <string.h>
%(includes)s

#define SET_STR(dst, s) do { (dst).len = (uint16_t)strlen(s); \
	memcpy((dst).data, (s), (dst).len + 1); } while (0)

static uint64_t mix(uint64_t h, uint64_t v)
{
	return (h ^ v) * 0x100000001b3ULL;
}

static uint64_t hash_bytes(uint64_t h, const void *p, unsigned int n)
{
	const unsigned char *c = p;
	unsigned int i;

	for (i = 0; i < n; i++)
		h = mix(h, c[i]);
	return h;
}

int main(int argc, char **argv)
{
	long cycles = argc > 1 ? atol(argv[1]) : 1000, k;
	uint32_t x = 2463534242u;
	uint64_t h = 1469598103934665603ULL;
%(setup)s
	for (k = 0; k < cycles; k++) {
		uint32_t r;

		x ^= x << 13;
		x ^= x >> 17;
		x ^= x << 5;
		r = x;
		(void)r;
%(inputs)s
%(call)s
%(hash)s
	}
	printf("checksum %%016llx fault %%d\n", (unsigned long long)h, %(fault)s);
	return 0;
}
"""


def compile_c(out: Path, name: str, srcs, includes, extra=()):
    cc = os.environ.get("CC", "gcc")
    if shutil.which(cc) is None:
        sys.exit(f"no C compiler '{cc}': install gcc")
    exe = out / name
    cmd = [cc, *CFLAGS, *extra, *[f"-I{i}" for i in includes], *map(str, srcs), "-o",
           str(exe), "-lm"]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"compile failed: {' '.join(cmd)}\n{p.stderr[-4000:]}")
    return exe


def driver_source(name, spec, iec: bool, gen=None, pou=None):
    if iec:
        prefix = f"prog_{name}"
        field = "inst.v_{}"
        includes = [f'#include "{gen.header_name}"']
        includes.append(f"IEC_POU_SCOPE void {prefix}_body(struct {prefix} *self, "
                        "struct iec_ctx *ctx) __attribute__((noinline, noclone));")
        includes += [f'#include "{gen.bodies[k][0]}"' for k in gen.order]
        # the frame area the program's body needs (iec_fault.h), sized and
        # set up as the simulator's task function does (iec2kmod/sim.py)
        setup = (f"\tstatic struct {prefix} inst;\n\tstatic struct iec_ctx ctx;\n"
                 f"\tstatic iec_u8 frames[IEC_FRAME_MAX({frame_need(pou)}, 16U)]\n"
                 "\t\t__attribute__((aligned(16)));\n"
                 f"\t{prefix}_init(&inst);\n\tiec_ctx_init(&ctx, 0);\n")
        call = (f"\t\tiec_ctx_cycle_begin(&ctx, (iec_s64)k * {CYCLE_NS}LL);\n"
                "\t\tiec_frame_area(&ctx, frames, sizeof(frames));\n"
                f"\t\t{prefix}_body(&inst, &ctx);\n"
                "\t\tif (ctx.fault != IEC_FAULT_NONE)\n\t\t\tbreak;")
        fault = "(int)ctx.fault"
    else:
        field = "s.{}"
        includes = ["#include <stdlib.h>", '#include "hand.h"',
                    f"#define hand_{name}_body __attribute__((noinline, noclone)) hand_{name}_body",
                    f'#include "{name}.c"', f"#undef hand_{name}_body"]
        init = f"hand_{name}_init(&s);" if f"hand_{name}_init" in \
            (HERE / f"{name}.c").read_text() else "memset(&s, 0, sizeof(s));"
        setup = (f"\tstatic struct hand_{name} s;\n\tstatic struct hand_ctx ctx;\n"
                 f"\t{init}\n")
        call = (f"\t\tctx.now_ns = (int64_t)k * {CYCLE_NS}LL;\n"
                f"\t\thand_{name}_body(&s, &ctx);\n\t\tif (ctx.fault)\n\t\t\tbreak;")
        fault = "ctx.fault"
    inputs = re.sub(r"F\((\w+)\)", lambda m: field.format(m.group(1)), spec["inputs"])
    hash_lines = []
    for o in spec["outputs"]:
        f = field.format(o)
        if o in spec.get("strings", ()):
            hash_lines.append(f"\t\th = hash_bytes(h, {f}.data, {f}.len);")
        else:
            hash_lines.append(f"\t\th = mix(h, (uint64_t)(int64_t)({f} * 1000));"
                              if o in ("out", "error") else
                              f"\t\th = mix(h, (uint64_t)(int64_t){f});")
    return DRIVER % {"includes": "\n".join(includes), "setup": setup, "inputs": inputs,
                     "call": call, "hash": "\n".join(hash_lines), "fault": fault}


def runtime_objects(out: Path):
    objs = []
    cc = os.environ.get("CC", "gcc")
    for s in RUNTIME_SOURCES:
        src = RUNTIME / s
        if not src.exists():
            continue
        obj = out / (src.stem + ".o")
        p = subprocess.run([cc, *CFLAGS, f"-I{RUNTIME}", "-c", str(src), "-o", str(obj)],
                           capture_output=True, text=True)
        if p.returncode != 0:
            sys.exit(f"runtime compile failed ({s}):\n{p.stderr[-3000:]}")
        objs.append(obj)
    return objs


def callgrind(exe: Path, fn: str, cycles: int, out: Path):
    if shutil.which("valgrind") is None:
        sys.exit("valgrind not found: install it (apt-get install valgrind)")
    cg = out / f"callgrind.{exe.name}"
    p = subprocess.run(["valgrind", "--tool=callgrind", f"--toggle-collect={fn}",
                        f"--callgrind-out-file={cg}", str(exe), str(cycles)],
                       capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"valgrind failed:\n{p.stderr[-3000:]}")
    total = None
    for line in cg.read_text().splitlines():
        if line.startswith(("summary:", "totals:")):
            total = int(line.split()[1])
    if total is None:
        sys.exit(f"no totals in {cg}")
    checksum = p.stdout.strip()
    return total, checksum


def measure(name, cycles, out: Path, rt_objs):
    spec = BENCHES[name]
    res = frontend.run([str(HERE / f"{name}.st")], use_cache=False)
    if not res.ok:
        sys.exit("\n".join(d.format() for d in res.diags.sorted()))
    gen = generate(res.project)
    d = out / name
    d.mkdir(parents=True, exist_ok=True)
    (d / gen.header_name).write_text(gen.header)
    for k in gen.order:
        fname, text = gen.bodies[k]
        (d / fname).write_text(text)
    (d / "driver_iec.c").write_text(driver_source(name, spec, True, gen,
                                                  res.project.pous[name.upper()]))
    (d / "driver_hand.c").write_text(driver_source(name, spec, False))
    exe_iec = compile_c(d, "iec", [d / "driver_iec.c", *rt_objs], [d, RUNTIME])
    exe_hand = compile_c(d, "hand", [d / "driver_hand.c"], [d, HERE])
    ir_iec, sum_iec = callgrind(exe_iec, f"prog_{name}_body", cycles, d)
    ir_hand, sum_hand = callgrind(exe_hand, f"hand_{name}_body", cycles, d)
    if sum_iec != sum_hand:
        sys.exit(f"{name}: the generated and the hand-written program disagree:\n"
                 f"  generated: {sum_iec}\n  hand:      {sum_hand}")
    if "fault 0" not in sum_iec:
        sys.exit(f"{name}: the program faulted: {sum_iec}")
    return ir_iec / cycles, ir_hand / cycles


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cycles", type=int, default=20000)
    ap.add_argument("--target", type=float, default=1.3)
    ap.add_argument("--keep", metavar="DIR", help="keep the generated files here")
    ap.add_argument("programs", nargs="*", default=list(BENCHES))
    ap.add_argument("--smoke", action="store_true",
                    help="a few seconds' run at a small size (CI: tests/benchmarks): 200 "
                         "cycles; the outputs must still agree, the target is printed, not "
                         "enforced")
    args = ap.parse_args()
    if args.smoke:
        args.cycles = 200
    tmp = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="scan_cost."))
    tmp.mkdir(parents=True, exist_ok=True)
    try:
        rt = runtime_objects(tmp)
        rows = []
        for name in args.programs:
            iec, hand = measure(name, args.cycles, tmp, rt)
            rows.append((name, iec, hand, iec / hand))
        print(f"{'program':<12}{'IEC instr/cycle':>18}{'hand instr/cycle':>18}{'ratio':>8}")
        for name, iec, hand, ratio in rows:
            print(f"{name:<12}{iec:>18.1f}{hand:>18.1f}{ratio:>8.2f}")
        worst = max(r[3] for r in rows)
        print(f"target <= {args.target}: {'met' if worst <= args.target else 'NOT met'}")
        return 0 if worst <= args.target or args.smoke else 1
    finally:
        if not args.keep:
            shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
