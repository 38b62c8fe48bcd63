/* SPDX-License-Identifier: GPL-2.0-only OR MIT */
/*
 * iec_real.h - REAL and LREAL: arithmetic, selection, conversions and the
 * numeric functions.
 *
 * FLOATING POINT.  Include this header only from objects compiled as
 * floating-point objects: in the kernel with -mhard-float -msse -msse2, and
 * called only between kernel_fpu_begin() and kernel_fpu_end() (which the
 * task loop does, from a non-FP object).  POUs that use no REAL/LREAL never
 * include it and link no FP object.
 *
 * Names: iec_<func>_real / iec_<func>_lreal (ADD SUB MUL DIV NEG ABS SQRT
 * LN LOG EXP EXPT SIN COS TAN ASIN ACOS ATAN ATAN2 SEL MAX MIN LIMIT MOVE
 * GT GE EQ LE LT NE), conversions iec_<from>_to_<to>, truncation
 * iec_<from>_trunc_<to> (REAL_TRUNC_DINT -> iec_real_trunc_dint; the
 * generic TRUNC(x) of a REAL into an INT is iec_real_trunc_int).
 *
 * Semantics:
 *  - Arithmetic is IEEE 754 (round to nearest even); x / 0.0 gives +-Inf
 *    or NaN and raises no fault.
 *  - MAX/MIN return NaN if an operand is NaN; LIMIT = MIN(MAX(IN, MN), MX).
 *  - REAL/LREAL -> integer types (SINT..ULINT, BYTE..LWORD: numeric value)
 *    round to the nearest integer, ties to even (REAL_TO_INT(2.5) = 2,
 *    REAL_TO_INT(3.5) = 4, REAL_TO_INT(-2.5) = -2).  Out-of-range values
 *    saturate to the type's limits, NaN converts to 0 (never undefined
 *    behaviour, unlike a C cast).  *_TRUNC_* truncate toward zero with the
 *    same saturation.
 *  - LREAL_TO_REAL rounds to nearest; beyond the REAL range it gives +-Inf.
 *  - REAL_TO_BOOL is (x <> 0.0) (NaN is TRUE); BOOL_TO_REAL is 0.0/1.0.
 *  - Time types <-> REAL/LREAL use the same units as the integer
 *    conversions (TIME ms, LTIME ns, TOD ms, DATE s, DT s, L* ns); to a time
 *    type rounds to the nearest nanosecond, ties to even, saturating.
 *  - MUL_TIME/DIV_TIME by an LREAL (iec_mul_time_lreal,
 *    iec_div_time_lreal): rounded to the ns and saturated; DIV_TIME by 0.0
 *    records IEC_FAULT_DIV_ZERO and returns T#0s.
 *  - Math function domains and accuracy: iec_math.c and README.md.
 *  - REAL_TO_STRING/LREAL_TO_STRING give the shortest decimal that reads
 *    back as the same value: '1.5', '0.1', '-3.0', '1.0E+20', '2.5E-7'
 *    (exponent form below 1E-5 and from 1E+15 (LREAL) / 1E+7 (REAL) up),
 *    'NaN', 'Inf', '-Inf', '-0.0'.  STRING_TO_REAL accepts IEC REAL and
 *    integer literals ('1.5', '-2E3', '1_000.5', 'REAL#3.5', 'NaN', 'Inf');
 *    invalid text converts to 0.0.
 */
#ifndef IEC_REAL_H
#define IEC_REAL_H

#include "iec_conv.h"
#include "iec_string.h"

/*
 * Division: x / 0.0 is defined (IEEE 754: +-Inf or NaN), but sparse folds a
 * quotient of two constants and warns "division by zero" on it; sparse sees
 * a declaration, the compiler the inline function.  Generated code divides
 * REAL values only through iec_div_real/lreal.
 */
#ifdef __CHECKER__
#define IEC__REAL_DIV(n, T) T iec_div_##n(T a, T b);
#else
#define IEC__REAL_DIV(n, T)						\
static inline T iec_div_##n(T a, T b) { return a / b; }
#endif

/* Arithmetic and selection */
#define IEC__DEF_REAL_OPS(n, T)						\
static inline T iec_add_##n(T a, T b) { return a + b; }		\
static inline T iec_sub_##n(T a, T b) { return a - b; }		\
static inline T iec_mul_##n(T a, T b) { return a * b; }		\
IEC__REAL_DIV(n, T)							\
static inline T iec_neg_##n(T a) { return -a; }				\
static inline T iec_abs_##n(T a) { return a < 0 ? -a : (a == 0 ? (T)0 : a); } \
static inline T iec_sel_##n(iec_bool g, T in0, T in1)			\
{									\
	return g ? in1 : in0;						\
}									\
static inline T iec_max_##n(T a, T b)					\
{									\
	if (a != a)							\
		return a;						\
	if (b != b)							\
		return b;						\
	return a >= b ? a : b;						\
}									\
static inline T iec_min_##n(T a, T b)					\
{									\
	if (a != a)							\
		return a;						\
	if (b != b)							\
		return b;						\
	return a <= b ? a : b;						\
}									\
static inline T iec_limit_##n(T mn, T in, T mx)				\
{									\
	return iec_min_##n(iec_max_##n(in, mn), mx);			\
}									\
static inline T iec_move_##n(T in) { return in; }			\
static inline iec_bool iec_gt_##n(T a, T b) { return a > b; }		\
static inline iec_bool iec_ge_##n(T a, T b) { return a >= b; }	\
static inline iec_bool iec_eq_##n(T a, T b) { return a == b; }	\
static inline iec_bool iec_le_##n(T a, T b) { return a <= b; }	\
static inline iec_bool iec_lt_##n(T a, T b) { return a < b; }		\
static inline iec_bool iec_ne_##n(T a, T b) { return a != b; }

IEC__DEF_REAL_OPS(real, iec_real)
IEC__DEF_REAL_OPS(lreal, iec_lreal)

/* Numeric functions (iec_math.c) */
double iec__sqrt(double x);
#define IEC__DECL_MATH(f)						\
iec_real iec_##f##_real(iec_real x);					\
iec_lreal iec_##f##_lreal(iec_lreal x);

IEC__DECL_MATH(sqrt)
IEC__DECL_MATH(exp)
IEC__DECL_MATH(ln)
IEC__DECL_MATH(log)
IEC__DECL_MATH(sin)
IEC__DECL_MATH(cos)
IEC__DECL_MATH(tan)
IEC__DECL_MATH(asin)
IEC__DECL_MATH(acos)
IEC__DECL_MATH(atan)

iec_real iec_atan2_real(iec_real y, iec_real x);
iec_lreal iec_atan2_lreal(iec_lreal y, iec_lreal x);
iec_real iec_expt_real(iec_real x, iec_real y);
iec_lreal iec_expt_lreal(iec_lreal x, iec_lreal y);
iec_real iec_expt_real_lint(iec_real x, iec_lint n);
iec_lreal iec_expt_lreal_lint(iec_lreal x, iec_lint n);

/* REAL <-> LREAL */
static inline iec_lreal iec_real_to_lreal(iec_real x)
{
	return x;
}

static inline iec_real iec_lreal_to_real(iec_lreal x)
{
	/* beyond FLT_MAX + ulp/2 the IEEE result is Inf; C leaves the cast
	 * undefined there, so it is spelt out */
	if (x >= 0x1.ffffffp+127)
		return __builtin_inff();
	if (x <= -0x1.ffffffp+127)
		return -__builtin_inff();
	return (iec_real)x;
}

/* Round to the nearest integer, ties to even (for |x| < 2^52; larger
 * values are integers already). */
static inline double iec__rint(double x)
{
	double a = x < 0 ? -x : x;

	if (!(a < 0x1p52))
		return x;
	a = (a + 0x1p52) - 0x1p52;
	return x < 0 ? -a : a;
}

/* Saturating conversions of an integral-valued (or, for TRUNC, any)
 * double: lo and hip1 are the type's minimum and maximum + 1. */
static inline iec_s64 iec__sat_signed(double r, double lo, double hip1,
				      iec_s64 tmin, iec_s64 tmax)
{
	if (r != r)
		return 0;
	if (r < lo)
		return tmin;
	if (r >= hip1)
		return tmax;
	return (iec_s64)r;
}

static inline iec_u64 iec__sat_unsigned(double r, double hip1, iec_u64 tmax)
{
	if (r != r || r < 0)
		return 0;
	if (r >= hip1)
		return tmax;
	return (iec_u64)r;
}

#define IEC__REAL_INT_S(n, T, LO, HIP1, MIN, MAX)			\
static inline T iec_lreal_to_##n(iec_lreal x)				\
{									\
	return (T)iec__sat_signed(iec__rint(x), LO, HIP1, MIN, MAX);	\
}									\
static inline T iec_real_to_##n(iec_real x)				\
{									\
	return iec_lreal_to_##n(x);					\
}									\
static inline T iec_lreal_trunc_##n(iec_lreal x)			\
{									\
	return (T)iec__sat_signed(x, LO, HIP1, MIN, MAX);		\
}									\
static inline T iec_real_trunc_##n(iec_real x)				\
{									\
	return iec_lreal_trunc_##n(x);					\
}									\
static inline iec_lreal iec_##n##_to_lreal(T v) { return (iec_lreal)v; } \
static inline iec_real iec_##n##_to_real(T v) { return (iec_real)v; }

#define IEC__REAL_INT_U(n, T, HIP1, MAX)				\
static inline T iec_lreal_to_##n(iec_lreal x)				\
{									\
	return (T)iec__sat_unsigned(iec__rint(x), HIP1, MAX);		\
}									\
static inline T iec_real_to_##n(iec_real x)				\
{									\
	return iec_lreal_to_##n(x);					\
}									\
static inline T iec_lreal_trunc_##n(iec_lreal x)			\
{									\
	return (T)iec__sat_unsigned(x, HIP1, MAX);			\
}									\
static inline T iec_real_trunc_##n(iec_real x)				\
{									\
	return iec_lreal_trunc_##n(x);					\
}									\
static inline iec_lreal iec_##n##_to_lreal(T v) { return (iec_lreal)v; } \
static inline iec_real iec_##n##_to_real(T v) { return (iec_real)v; }

IEC__REAL_INT_S(sint, iec_sint, -0x1p7, 0x1p7, IEC_S8_MIN, IEC_S8_MAX)
IEC__REAL_INT_S(int, iec_int, -0x1p15, 0x1p15, IEC_S16_MIN, IEC_S16_MAX)
IEC__REAL_INT_S(dint, iec_dint, -0x1p31, 0x1p31, IEC_S32_MIN, IEC_S32_MAX)
IEC__REAL_INT_S(lint, iec_lint, -0x1p63, 0x1p63, IEC_S64_MIN, IEC_S64_MAX)
IEC__REAL_INT_U(usint, iec_usint, 0x1p8, IEC_U8_MAX)
IEC__REAL_INT_U(uint, iec_uint, 0x1p16, IEC_U16_MAX)
IEC__REAL_INT_U(udint, iec_udint, 0x1p32, IEC_U32_MAX)
IEC__REAL_INT_U(ulint, iec_ulint, 0x1p64, IEC_U64_MAX)
IEC__REAL_INT_U(byte, iec_byte, 0x1p8, IEC_U8_MAX)
IEC__REAL_INT_U(word, iec_word, 0x1p16, IEC_U16_MAX)
IEC__REAL_INT_U(dword, iec_dword, 0x1p32, IEC_U32_MAX)
IEC__REAL_INT_U(lword, iec_lword, 0x1p64, IEC_U64_MAX)

static inline iec_bool iec_real_to_bool(iec_real x) { return x != 0; }
static inline iec_bool iec_lreal_to_bool(iec_lreal x) { return x != 0; }
static inline iec_real iec_bool_to_real(iec_bool b) { return b ? 1.0f : 0.0f; }
static inline iec_lreal iec_bool_to_lreal(iec_bool b) { return b ? 1.0 : 0.0; }

/* Time types <-> REAL/LREAL (kind as in iec_conv.h) */
static inline iec_s64 iec__real_to_time(double x, double unit, int kind)
{
	iec_s64 v = iec__sat_signed(iec__rint(x * unit), -0x1p63, 0x1p63,
				    IEC_S64_MIN, IEC_S64_MAX);

	if (kind == 2)
		return iec__wrap_sub(v, iec__floormod(v, IEC_NS_PER_DAY));
	if (kind == 3)
		return iec__floormod(v, IEC_NS_PER_DAY);
	return v;
}

#define IEC__DEF_TIME_REAL(tn, tT, unit, kind, ...)			\
static inline iec_lreal iec_##tn##_to_lreal(tT v)			\
{									\
	return (double)v / (double)(unit);				\
}									\
static inline iec_real iec_##tn##_to_real(tT v)				\
{									\
	return (iec_real)iec_##tn##_to_lreal(v);			\
}									\
static inline tT iec_lreal_to_##tn(iec_lreal x)				\
{									\
	return iec__real_to_time(x, (double)(unit), kind);		\
}									\
static inline tT iec_real_to_##tn(iec_real x)				\
{									\
	return iec__real_to_time(x, (double)(unit), kind);		\
}

IEC__TIME_LIST(IEC__DEF_TIME_REAL, 0)

static inline iec_time iec_mul_time_lreal(iec_time t, iec_lreal f)
{
	return iec__real_to_time((double)t * f, 1.0, 0);
}

static inline iec_time iec_div_time_lreal(struct iec_ctx *ctx, iec_time t,
					  iec_lreal f)
{
	if (iec_unlikely(f == 0)) {
		iec_fault_raise(ctx, IEC_FAULT_DIV_ZERO);
		return 0;
	}
	return iec__real_to_time((double)t / f, 1.0, 0);
}

static inline iec_time iec_mul_time_real(iec_time t, iec_real f)
{
	return iec_mul_time_lreal(t, f);
}

static inline iec_time iec_div_time_real(struct iec_ctx *ctx, iec_time t,
					 iec_real f)
{
	return iec_div_time_lreal(ctx, t, f);
}

static inline iec_ltime iec_mul_ltime_lreal(iec_ltime t, iec_lreal f)
{
	return iec_mul_time_lreal(t, f);
}

static inline iec_ltime iec_div_ltime_lreal(struct iec_ctx *ctx,
					    iec_ltime t, iec_lreal f)
{
	return iec_div_time_lreal(ctx, t, f);
}

/* String conversions (iec_real.c) */
void iec_real_to_string(struct iec_strbuf dst, iec_real v);
void iec_lreal_to_string(struct iec_strbuf dst, iec_lreal v);
void iec_real_to_wstring(struct iec_wstrbuf dst, iec_real v);
void iec_lreal_to_wstring(struct iec_wstrbuf dst, iec_lreal v);
iec_real iec_string_to_real(struct iec_strv s);
iec_lreal iec_string_to_lreal(struct iec_strv s);
iec_real iec_wstring_to_real(struct iec_wstrv s);
iec_lreal iec_wstring_to_lreal(struct iec_wstrv s);

#endif /* IEC_REAL_H */
