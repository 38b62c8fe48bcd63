// SPDX-License-Identifier: GPL-2.0-only OR MIT
/*
 * iec_io_real.c - REAL/LREAL scaling of a bound analog channel (iec_io.c,
 * iec2kmod/iomap.py).  Built with the FPU flags (iec2kmod/kmod/tree.py
 * FP_FLAGS: SSE2, no x87) and called only between kernel_fpu_begin() and
 * kernel_fpu_end(), from the non-FP iec_io.c.
 *
 * The arithmetic is IEEE binary64, operation by operation, exactly as
 * iec2kmod.iomap.phys_of() and raw_of() compute it in Python, so both give
 * the same bits for every sample:
 *
 *   input   v = lo + raw * (hi - lo) / maxdata   (double; a REAL gets v
 *                                                 rounded to nearest float)
 *   output  t = (v - lo) * maxdata / (hi - lo) + 0.5   (v widened to double)
 *           raw = 0 if t < 1 or t is NaN, maxdata if t >= maxdata,
 *                 floor(t) otherwise (nearest sample, halves up)
 */
#include <linux/string.h>
#include <linux/types.h>

#include "iec_io_real.h"

static double iec_io_double(u64 bits)
{
	double d;

	memcpy(&d, &bits, sizeof(d));
	return d;
}

void iec_io_real_store(const struct iec_io_scale *s, void *var, u8 size, u32 raw)
{
	double lo = iec_io_double(s->lo), hi = iec_io_double(s->hi);
	double v = lo + (double)raw * (hi - lo) / (double)s->maxdata;

	if (size == sizeof(float)) {
		float f = (float)v;

		memcpy(var, &f, sizeof(f));
	} else {
		memcpy(var, &v, sizeof(v));
	}
}

u32 iec_io_real_load(const struct iec_io_scale *s, const void *var, u8 size)
{
	double lo = iec_io_double(s->lo), hi = iec_io_double(s->hi);
	double v, t;

	if (size == sizeof(float)) {
		float f;

		memcpy(&f, var, sizeof(f));
		v = f;
	} else {
		memcpy(&v, var, sizeof(v));
	}
	t = (v - lo) * (double)s->maxdata / (hi - lo) + 0.5;
	if (!(t >= 1.0))
		return 0;
	if (t >= (double)s->maxdata)
		return s->maxdata;
	return (u32)t;
}
