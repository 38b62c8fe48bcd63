/* SPDX-License-Identifier: GPL-2.0-only OR MIT */
/*
 * iec_gen.h - what generated POU code needs beyond the runtime library.
 *
 * IEC_POU_SCOPE: storage class of POU functions.  Program-type modules keep
 * every POU function static (the GFT slot is their only way in), so two
 * versions of a program type can be loaded side by side; the host
 * simulation defines it empty to export the bodies.
 */
#ifndef IEC_GEN_H
#define IEC_GEN_H

#include "iec_types.h"
#include "iec_fault.h"
#include "iec_int.h"
#include "iec_conv.h"
#include "iec_time.h"
#include "iec_string.h"
#include "iec_std_fb.h"
#include "iec_real.h"

#ifndef IEC_POU_SCOPE
#define IEC_POU_SCOPE static __attribute__((__unused__))
#endif

/* Views and destinations of fixed-length string variables. */
#define IEC_STRV(s)							\
	iec_strv_make((s).data, (s).len, (iec_u16)(sizeof((s).data) - 1))
#define IEC_STRBUF(s)							\
	((struct iec_strbuf){ .p = (s).data, .len = &(s).len,		\
			      .cap = (iec_u16)(sizeof((s).data) - 1) })
#define IEC_WSTRV(s)							\
	iec_wstrv_make((s).data, (s).len,				\
		       (iec_u16)(sizeof((s).data) / sizeof((s).data[0]) - 1))
#define IEC_WSTRBUF(s)							\
	((struct iec_wstrbuf){ .p = (s).data, .len = &(s).len,		\
			       .cap = (iec_u16)(sizeof((s).data) /		\
						sizeof((s).data[0]) - 1) })

/*
 * Loop budget of a FOR loop whose iteration count n is known when it
 * starts: the n iterations are charged at once (IEC_LOOP_CHARGE, which
 * records IEC_FAULT_LOOP and returns like IEC_LOOP_TICK when the budget is
 * short), an EXIT gives back the iterations not run (IEC_LOOP_REFUND).
 */
#define IEC_LOOP_CHARGE(ctx, pou, line, n)				\
	do {								\
		if (iec_unlikely((ctx)->loop_budget < (iec_u32)(n))) {	\
			(ctx)->loop_budget = 0;				\
			iec_fault_raise((ctx), IEC_FAULT_LOOP);		\
			iec_fault_locate((ctx), (pou), (line));		\
			return;						\
		}							\
		(ctx)->loop_budget -= (iec_u32)(n);			\
	} while (0)

#define IEC_LOOP_CHARGE_RET(ctx, pou, line, n, retval)			\
	do {								\
		if (iec_unlikely((ctx)->loop_budget < (iec_u32)(n))) {	\
			(ctx)->loop_budget = 0;				\
			iec_fault_raise((ctx), IEC_FAULT_LOOP);		\
			iec_fault_locate((ctx), (pou), (line));		\
			return (retval);				\
		}							\
		(ctx)->loop_budget -= (iec_u32)(n);			\
	} while (0)

#define IEC_LOOP_REFUND(ctx, n)	((ctx)->loop_budget += (iec_u32)(n))

/*
 * Fast paths for STRING that the code generator uses instead of a call
 * into iec_string.c where the result is the same (see iec_string.h for the
 * semantics): set and append with truncation at the capacity, the decimal
 * form of an integer appended, substring views without a copy, equality.
 * Operands may alias the destination.
 */
static inline void iec_str_set(struct iec_strbuf d, struct iec_strv s)
{
	unsigned int n = s.len <= d.cap ? s.len : d.cap;

	if (n && d.p != s.p)
		iec_memmove(d.p, s.p, n);
	d.p[n] = 0;
	*d.len = (iec_u16)n;
}

static inline void iec_str_append(struct iec_strbuf d, struct iec_strv s)
{
	unsigned int len = *d.len <= d.cap ? *d.len : d.cap;
	unsigned int n = s.len <= d.cap - len ? s.len : d.cap - len;

	if (n)
		iec_memmove(d.p + len, s.p, n);
	len += n;
	d.p[len] = 0;
	*d.len = (iec_u16)len;
}

/* INT_TO_STRING(v) appended: the decimal digits, '-' for a negative value */
static inline void iec_str_append_s32(struct iec_strbuf d, iec_s32 v)
{
	char buf[12], *p = buf + sizeof(buf);
	iec_u32 u = v < 0 ? 0U - (iec_u32)v : (iec_u32)v;

	do {
		*--p = (char)('0' + u % 10);
		u /= 10;
	} while (u);
	if (v < 0)
		*--p = '-';
	iec_str_append(d, iec_strv_make(p, (iec_u16)(buf + sizeof(buf) - p),
					(iec_u16)sizeof(buf)));
}

static inline void iec_str_append_u64(struct iec_strbuf d, iec_u64 u)
{
	char buf[20], *p = buf + sizeof(buf);

	do {
		*--p = (char)('0' + u % 10);
		u /= 10;
	} while (u);
	iec_str_append(d, iec_strv_make(p, (iec_u16)(buf + sizeof(buf) - p),
					(iec_u16)sizeof(buf)));
}

static inline void iec_str_append_s64(struct iec_strbuf d, iec_s64 v)
{
	if (v < 0) {
		iec_str_append(d, iec_strv_make("-", 1, 1));
		iec_str_append_u64(d, 0ULL - (iec_u64)v);
	} else {
		iec_str_append_u64(d, (iec_u64)v);
	}
}

static inline iec_u16 iec__str_take(iec_lint l, iec_u16 n)
{
	return l <= 0 ? 0 : ((iec_u64)l >= n ? n : (iec_u16)l);
}

/* LEFT, RIGHT and MID as views into their input */
static inline struct iec_strv iec_strv_left(struct iec_strv s, iec_lint l)
{
	s.len = iec__str_take(l, s.len);
	return s;
}

static inline struct iec_strv iec_strv_right(struct iec_strv s, iec_lint l)
{
	iec_u16 k = iec__str_take(l, s.len);

	s.p += s.len - k;
	s.len = k;
	return s;
}

static inline struct iec_strv iec_strv_mid(struct iec_strv s, iec_lint l,
					   iec_lint pos)
{
	if (pos < 1 || (iec_u64)pos > s.len) {
		s.len = 0;
		return s;
	}
	s.p += pos - 1;
	s.len = iec__str_take(l, (iec_u16)(s.len - (pos - 1)));
	return s;
}

/*
 * Byte by byte, not memcmp: inlined with a constant on one side, GCC
 * checks a memcmp's bound against each buffer on its own and rejects a
 * comparison it cannot see is guarded by a.len == b.len
 * (-Wstringop-overread: MID('q$'', n, 1) <> CONCAT('Hello', '$N', 'z z')).
 */
static inline iec_bool iec_str_eq(struct iec_strv a, struct iec_strv b)
{
	iec_u16 i;

	if (a.len != b.len)
		return 0;
	for (i = 0; i < a.len; i++)
		if (a.p[i] != b.p[i])
			return 0;
	return 1;
}

#endif /* IEC_GEN_H */
