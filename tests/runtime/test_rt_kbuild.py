# SPDX-License-Identifier: MIT
"""The runtime builds in the kernel: a module that includes every runtime
header and takes the address of every runtime function (so each one is
compiled for the kernel), calls a few, and runs the floating-point ones in
a separate object built with -mhard-float -msse -msse2 between
kernel_fpu_begin() and kernel_fpu_end().  Built with W=1; any warning
(compiler or modpost, e.g. an undefined symbol such as a libm call) fails.
The host cannot load the module; building it is the test."""
import re
import shutil
import subprocess

import pytest

from rt_helpers import RUNTIME

pytestmark = pytest.mark.kbuild


INT_HEADERS = ["iec_platform.h", "iec_types.h", "iec_fault.h", "iec_int.h",
               "iec_time.h", "iec_conv.h", "iec_string.h", "iec_std_fb.h"]
FP_HEADERS = INT_HEADERS + ["iec_real.h"]
SOURCES = ["iec_string.c", "iec_std_fb.c", "iec_math.c", "iec_real.c"]
FP_SOURCES = ["iec_math.c", "iec_real.c"]
FP_FLAGS = "-mhard-float -msse -msse2"


def kdir():
    """The PREEMPT_RT kbuild directory the project itself finds (whatever
    version apt installed), or the tier fails saying what to install."""
    from iec2kmod import kbuild
    try:
        return kbuild.find_kdir()
    except kbuild.KbuildError as exc:
        pytest.fail(f"kernel headers not found: {exc}")


DECL = re.compile(
    r"(?:^|[;{}]\s*)(?:static\s+inline\s+)?(?:const\s+)?"
    r"(?:struct\s+\w+|enum\s+\w+|\w+)\s*\*?\s*(iec_\w+)\s*\(")


def functions(headers):
    """Names of the functions the headers define or declare (read from the
    preprocessed text, so macro-generated families are included)."""
    src = "".join(f'#include "{h}"\n' for h in headers)
    out = subprocess.run(["gcc", "-std=gnu11", "-E", "-P", "-I", str(RUNTIME),
                          "-x", "c", "-"], input=src, capture_output=True,
                         text=True, check=True).stdout
    names = sorted(set(DECL.findall(out)))
    assert len(names) > 100, names
    return names


def table(names):
    body = ",\n".join(f"\t(const void *){n}" for n in names)
    return ("static const void *const iec_rt_funcs[] __used = {\n"
            + body + ",\n};\n")


MAIN = r'''// SPDX-License-Identifier: GPL-2.0-only OR MIT
#include <linux/module.h>
#include <linux/kernel.h>
#include <asm/fpu/api.h>
%(includes)s
#include "rt_fp.h"

%(table)s
IEC_DECLARE_STRING(16);

static struct iec_ctx ctx;
static struct iec_fb_ton ton;
static struct iec_string_16 s;

static int __init iec_rt_check_init(void)
{
	int fp;

	iec_ctx_init(&ctx, 100);
	iec_ctx_cycle_begin(&ctx, 1000);
	ton.in = 1;
	ton.pt = 10;
	iec_fb_ton(&ton, &ctx);
	iec_concat_string(IEC_SB(s), IEC_SLIT("ab"), IEC_SLIT("cd"));
	iec_dint_to_string(IEC_SB(s), iec_div_dint(&ctx, 7, 0));
	kernel_fpu_begin();
	fp = iec_rt_check_fp();
	kernel_fpu_end();
	pr_info("iec runtime: %%zu functions, fault %%d, '%%s', fp %%d\n",
		ARRAY_SIZE(iec_rt_funcs), ctx.fault, s.data, fp);
	return 0;
}

static void __exit iec_rt_check_exit(void)
{
}

module_init(iec_rt_check_init);
module_exit(iec_rt_check_exit);
MODULE_LICENSE("Dual MIT/GPL");
MODULE_DESCRIPTION("iec2kmod runtime kernel build check");
'''

FP = r'''// SPDX-License-Identifier: GPL-2.0-only OR MIT
/* floating-point object: called between kernel_fpu_begin/end only */
#include <linux/compiler.h>
#include "iec_real.h"
#include "rt_fp.h"

%(table)s
int iec_rt_check_fp(void)
{
	volatile double x = 0.5;
	struct iec_string s;

	iec_lreal_to_string(IEC_SB(s), iec_sin_lreal(x) + iec_expt_lreal(x, 3.0));
	return iec_lreal_to_dint(iec_sqrt_lreal(x) * 1000.0) + s.len +
	       iec_real_to_int(iec_atan2_real(1.0f, (float)x)) +
	       (int)sizeof(iec_rt_fp_funcs);
}
'''

KBUILD = """obj-m := iec_rt_check.o
iec_rt_check-y := rt_main.o rt_fp.o %(objs)s
ccflags-y += -I$(src)
%(fpflags)s
"""


def test_runtime_builds_in_kernel_w1(tmp_path):
    kd = kdir()
    if shutil.which("make") is None:
        pytest.fail("make is required: apt-get install make")
    for f in RUNTIME.iterdir():
        if f.suffix in (".c", ".h"):
            shutil.copy(f, tmp_path / f.name)
    int_names = functions(INT_HEADERS)
    fp_names = [n for n in functions(FP_HEADERS) if n not in set(int_names)]
    assert "iec_sin_lreal" in fp_names and "iec_fb_ton" in int_names
    (tmp_path / "rt_fp.h").write_text(
        "/* SPDX-License-Identifier: GPL-2.0-only OR MIT */\n"
        "#ifndef RT_FP_H\n#define RT_FP_H\nint iec_rt_check_fp(void);\n"
        "#endif\n")
    (tmp_path / "rt_main.c").write_text(MAIN % {
        "includes": "".join(f'#include "{h}"\n' for h in INT_HEADERS),
        "table": table(int_names)})
    (tmp_path / "rt_fp.c").write_text(FP % {
        "table": table(fp_names).replace("iec_rt_funcs", "iec_rt_fp_funcs")})
    objs = " ".join(s.replace(".c", ".o") for s in SOURCES)
    fpflags = "\n".join(f"CFLAGS_{o}.o += {FP_FLAGS}" for o in
                        ["rt_fp"] + [s[:-2] for s in FP_SOURCES])
    (tmp_path / "Kbuild").write_text(KBUILD % {"objs": objs,
                                               "fpflags": fpflags})
    r = subprocess.run(["make", "-C", kd, f"M={tmp_path}", "W=1", "modules"],
                       capture_output=True, text=True, timeout=600)
    out = r.stdout + r.stderr
    assert r.returncode == 0, out
    assert (tmp_path / "iec_rt_check.ko").exists(), out
    bad = [ln for ln in out.splitlines()
           if re.search(r"warning|undefined", ln, re.I)]
    assert not bad, "\n".join(bad)
    # nothing but kernel symbols is imported: no libm, no libgcc helpers
    nm = subprocess.run(["nm", "-u", str(tmp_path / "iec_rt_check.ko")],
                        capture_output=True, text=True, check=True).stdout
    undef = {ln.split()[-1] for ln in nm.splitlines() if ln.strip()}
    libm = {"sin", "cos", "tan", "exp", "log", "log10", "pow", "sqrt",
            "atan", "atan2", "asin", "acos", "fmod", "floor", "__divti3",
            "__udivti3", "__modti3", "__umodti3"}
    assert not (undef & libm), undef & libm
