/* SPDX-License-Identifier: GPL-2.0-only OR MIT */
/*
 * iec_io_real.h - REAL/LREAL scaling of bound analog channels: the
 * functions of iec_io_real.c, the one object of a resource module built
 * with the FPU flags.  Call them only between kernel_fpu_begin() and
 * kernel_fpu_end() (iec_io.c does).  No floating-point type crosses this
 * interface: a non-FP object includes it.
 */
#ifndef IEC_IO_REAL_H
#define IEC_IO_REAL_H

#include <linux/types.h>

/*
 * A channel's range lo..hi (the bit patterns of two IEEE binary64) and its
 * largest sample maxdata = 2**bits - 1.
 */
struct iec_io_scale {
	u64 lo;
	u64 hi;
	u32 maxdata;
};

/* raw -> *var, a float (size 4) or a double (size 8) */
void iec_io_real_store(const struct iec_io_scale *s, void *var, u8 size, u32 raw);
/* *var -> raw, rounded, clamped to 0..maxdata; NaN gives 0 */
u32 iec_io_real_load(const struct iec_io_scale *s, const void *var, u8 size);

#endif /* IEC_IO_REAL_H */
