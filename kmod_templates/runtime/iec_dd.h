/* SPDX-License-Identifier: GPL-2.0-only OR MIT */
/*
 * iec_dd.h - internal floating-point helpers of the runtime (bit access,
 * scaling, double-double arithmetic after Dekker and Knuth).  Included
 * only by the runtime's floating-point objects (iec_math.c, iec_real.c),
 * never by generated code.
 */
#ifndef IEC_DD_H
#define IEC_DD_H

#include "iec_types.h"

typedef union {
	double d;
	iec_u64 u;
} iec__dbits;

static inline iec_u64 iec__asu64(double x)
{
	iec__dbits b = { .d = x };

	return b.u;
}

static inline double iec__asdouble(iec_u64 u)
{
	iec__dbits b = { .u = u };

	return b.d;
}

#define IEC__NAN_D	(__builtin_nan(""))
#define IEC__INF_D	(__builtin_inf())

static inline int iec__isnan_d(double x)
{
	return x != x;
}

static inline double iec__fabs_d(double x)
{
	return iec__asdouble(iec__asu64(x) & ~(1ULL << 63));
}

static inline double iec__copysign_d(double x, double s)
{
	return iec__asdouble((iec__asu64(x) & ~(1ULL << 63)) |
			     (iec__asu64(s) & (1ULL << 63)));
}

/* x * 2^n, with gradual underflow and overflow to Inf. */
static inline double iec__scalbn_d(double x, int n)
{
	if (n > 1023) {
		x *= 0x1p1023;
		n -= 1023;
		if (n > 1023) {
			x *= 0x1p1023;
			n -= 1023;
			if (n > 1023)
				n = 1023;
		}
	} else if (n < -1022) {
		x *= 0x1p-1022 * 0x1p53;
		n += 1022 - 53;
		if (n < -1022) {
			x *= 0x1p-1022 * 0x1p53;
			n += 1022 - 53;
			if (n < -1022)
				n = -1022;
		}
	}
	return x * iec__asdouble((iec_u64)(0x3ff + n) << 52);
}

/* ---------------------------------------------------------------------
 * Double-double helpers (value = hi + lo, |lo| <= ulp(hi) / 2).
 */
struct iec__dd {
	double hi, lo;
};

static inline struct iec__dd iec__two_sum(double a, double b)
{
	double s = a + b, bb = s - a;
	struct iec__dd r = { s, (a - (s - bb)) + (b - bb) };

	return r;
}

static inline struct iec__dd iec__fast_two_sum(double a, double b)
{
	double s = a + b;
	struct iec__dd r = { s, b - (s - a) };

	return r;
}

/* Veltkamp iec__split and Dekker's exact product (no FMA needed). */
static inline void iec__split(double a, double *hi, double *lo)
{
	double c = 134217729.0 * a;	/* 2^27 + 1 */

	*hi = c - (c - a);
	*lo = a - *hi;
}

static inline struct iec__dd iec__two_prod(double a, double b)
{
	double ah, al, bh, bl, p = a * b;
	struct iec__dd r;

	iec__split(a, &ah, &al);
	iec__split(b, &bh, &bl);
	r.hi = p;
	r.lo = ((ah * bh - p) + ah * bl + al * bh) + al * bl;
	return r;
}

static inline struct iec__dd iec__dd_add(struct iec__dd a, struct iec__dd b)
{
	struct iec__dd s = iec__two_sum(a.hi, b.hi);

	s.lo += a.lo + b.lo;
	return iec__fast_two_sum(s.hi, s.lo);
}

static inline struct iec__dd iec__dd_mul(struct iec__dd a, struct iec__dd b)
{
	struct iec__dd p = iec__two_prod(a.hi, b.hi);

	p.lo += a.hi * b.lo + a.lo * b.hi;
	return iec__fast_two_sum(p.hi, p.lo);
}

static inline struct iec__dd iec__dd_mul_d(struct iec__dd a, double b)
{
	struct iec__dd p = iec__two_prod(a.hi, b);

	p.lo += a.lo * b;
	return iec__fast_two_sum(p.hi, p.lo);
}

static inline struct iec__dd iec__dd_div(struct iec__dd a, struct iec__dd b)
{
	double q1 = a.hi / b.hi, q2;
	struct iec__dd r = iec__dd_add(a, iec__dd_mul_d(b, -q1));

	q2 = r.hi / b.hi;
	r = iec__dd_add(r, iec__dd_mul_d(b, -q2));
	return iec__dd_add(iec__fast_two_sum(q1, q2),
			   (struct iec__dd){ r.hi / b.hi, 0 });
}

#endif /* IEC_DD_H */
