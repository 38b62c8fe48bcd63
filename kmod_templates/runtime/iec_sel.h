/* SPDX-License-Identifier: GPL-2.0-only OR MIT */
/*
 * iec_sel.h - what selectively executed blocks need (iec2kmod --selective).
 *
 * The generated <prefix>_run() functions (iec2kmod/codegen/selective.py)
 * compare a block's argument set with the copy taken when it was last
 * evaluated, byte for byte: equal bytes give equal results, which value
 * comparison would not promise (a REAL -0.0 equals 0.0 but divides
 * differently).  The per-task state of selective execution lives in
 * struct iec_ctx (iec_fault.h): sel_epoch, sel_changed and the counters.
 */
#ifndef IEC_SEL_H
#define IEC_SEL_H

#include "iec_types.h"

/*
 * Do the @n bytes at @a and @b differ?  Always inlined: @n is a constant
 * at every call, and the word loads fold into a few compares.
 */
static inline __attribute__((__always_inline__)) bool
iec_sel_ne(const void *a, const void *b, iec_size_t n)
{
	const iec_u8 *p = a;
	const iec_u8 *q = b;
	iec_u64 x8, y8;
	iec_u32 x4, y4;
	iec_u16 x2, y2;

	/* unrolled: n is a constant, no loop counter is left at the call */
	_Pragma("GCC unroll 16")
	while (n >= 8) {
		iec_memcpy(&x8, p, 8);
		iec_memcpy(&y8, q, 8);
		if (x8 != y8)
			return true;
		p += 8;
		q += 8;
		n -= 8;
	}
	if (n >= 4) {
		iec_memcpy(&x4, p, 4);
		iec_memcpy(&y4, q, 4);
		if (x4 != y4)
			return true;
		p += 4;
		q += 4;
		n -= 4;
	}
	if (n >= 2) {
		iec_memcpy(&x2, p, 2);
		iec_memcpy(&y2, q, 2);
		if (x2 != y2)
			return true;
		p += 2;
		q += 2;
		n -= 2;
	}
	return n && *p != *q;
}

/*
 * A block whose arguments changed at IEC_SEL_BUSY_AFTER evaluations in a
 * row is evaluated plainly (no comparison, no copy) in the next
 * IEC_SEL_BUSY task cycles before it is checked again; if they changed
 * again at the next IEC_SEL_BUSY_AFTER evaluations, the next plain period
 * is twice as long, up to IEC_SEL_BUSY << IEC_SEL_BUSY_LEVELS cycles (a
 * full evaluation starts again from IEC_SEL_BUSY): what selective
 * execution costs when everything changes.
 */
#define IEC_SEL_BUSY_AFTER	2
#define IEC_SEL_BUSY		16
#define IEC_SEL_BUSY_LEVELS	4

/*
 * The token of a leaf block between the start of an evaluation that may
 * settle it and the end of its body: <prefix>_run() sets IEC_SEL_TOKEN if
 * the body ended without fault and left its written state as it was.  Even,
 * so never a module's IEC_SEL_TOKEN (odd): left by a fault, it is not
 * settled, in this module or in the next one after a swap.
 */
#define IEC_SEL_PENDING		(~IEC_SEL_TOKEN)

/* Bytes from the start of an instance to the end of its last input. */
#define IEC_SEL_SPAN(type, last)					\
	(__builtin_offsetof(type, last) + sizeof(((type *)0)->last))

#endif /* IEC_SEL_H */
