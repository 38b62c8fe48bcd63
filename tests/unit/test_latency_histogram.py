"""The kernel's release latency histogram (iec_hist_bucket() in
kmod_templates/kernel/iec_kmod.h, log-linear with an overflow bucket) and
benchmarks/jitter.py's decoding of it agree for every latency up to 20 ms:
the kernel function is compiled in user space with a few shims and run."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benchmarks"))

import jitter  # noqa: E402

SHIM = """
#include <stdio.h>
#include <stdint.h>
typedef uint64_t u64; typedef uint32_t u32; typedef int64_t s64;
#define NSEC_PER_USEC 1000ULL
#define ilog2(x) (63 - __builtin_clzll(x))
#define min_t(t, a, b) ((t)(a) < (t)(b) ? (t)(a) : (t)(b))
#define IEC_HIST_BUCKETS %d
%s
int main(void)
{
	for (s64 us = 0; us < 20000; us++)
		printf("%%u %%u\\n", iec_hist_bucket(us * 1000 + 999), iec_hist_bucket(us * 1000));
	printf("%%u\\n", iec_hist_bucket(-5));
	return 0;
}
"""


def test_kernel_buckets_match_the_benchmarks_decoder(tmp_path):
    cc = shutil.which("gcc") or shutil.which("cc")
    assert cc, "no C compiler: apt-get install gcc"
    header = (ROOT / "kmod_templates" / "kernel" / "iec_kmod.h").read_text()
    n = int(re.search(r"#define IEC_HIST_BUCKETS\s+(\d+)", header).group(1))
    assert n == jitter.BUCKETS
    fn = re.search(r"static inline u32 iec_hist_bucket\(s64 ns\)\n\{.*?\n\}\n", header, re.S)
    assert fn, "iec_hist_bucket() not found in iec_kmod.h"
    (tmp_path / "h.c").write_text(SHIM % (n, fn.group(0)))
    subprocess.run([cc, "-O1", "-o", str(tmp_path / "h"), str(tmp_path / "h.c")], check=True)
    out = subprocess.run([str(tmp_path / "h")], capture_output=True, text=True,
                         check=True).stdout.split("\n")
    for us, line in enumerate(out[:20000]):
        hi, lo = (int(x) for x in line.split())
        assert hi == lo == jitter.bucket_of(us), (us, hi, lo, jitter.bucket_of(us))
        a, b = jitter.bucket_bounds(hi)
        assert a <= us < b, (us, hi, a, b)
    assert int(out[20000]) == 0
    assert jitter.bucket_of(7168) == jitter.bucket_of(10 ** 7) == n - 1   # the overflow


def test_percentiles_from_a_histogram():
    d = jitter.ours("t", [0, 90, 9] + [0] * 60 + [1], 100, 100 * 1500, 9_000_000, 0)
    assert d.q(0.5) == 2 and d.q(0.99) == 3 and d.q(0.999) == 9000.0
    assert d.overflow == 1 and d.max == 9000.0 and d.min == 1
