/* SPDX-License-Identifier: GPL-2.0-only OR MIT */
/*
 * iec_int.h - integer, bit string and selection standard functions.
 *
 * Naming: iec_<function>_<operand type>, all lower case, e.g. iec_add_int,
 * iec_shl_word, iec_limit_udint.  Functions that can fault take the task
 * context first: iec_div_dint(ctx, a, b).
 *
 * Semantics:
 *  - ADD, SUB, MUL, NEG (unary minus), ABS wrap around in two's complement
 *    (the arithmetic is done in unsigned types, so it is never undefined):
 *    ADD_INT(32767, 1) = -32768, ABS_INT(-32768) = -32768.
 *  - DIV truncates toward zero; MOD has the sign of the dividend
 *    (IN1 - (IN1 / IN2) * IN2).  A zero divisor records IEC_FAULT_DIV_ZERO
 *    and returns 0.  MIN / -1 wraps to MIN; MIN MOD -1 is 0.
 *  - SHL/SHR by N outside 0..width-1 give 0 (a negative N too); ROL/ROR by
 *    N rotate by N modulo the width (a negative N rotates the other way).
 *  - BOOL functions return 0 or 1 for any non-zero input.
 *  - SEL(G, IN0, IN1), MAX, MIN, LIMIT(MN, IN, MX) = MIN(MAX(IN, MN), MX),
 *    MOVE, and the comparisons GT GE EQ LE LT NE (two operands; the code
 *    generator chains the extensible forms: GT(a, b, c) = a > b AND b > c)
 *    exist for every integer, bit string, BOOL and time/date type.
 *  - MUX is emitted by the code generator with iec_mux_index (iec_fault.h).
 */
#ifndef IEC_INT_H
#define IEC_INT_H

#include "iec_fault.h"

/* T: C type, U: unsigned of same width, W: unsigned type wide enough for
 * an unpromoted product (at least unsigned int).  The result is masked to U
 * before it is narrowed: sparse warns "cast truncates bits from constant
 * value" on a narrowing cast once a call with constants is inlined. */
#define IEC__DEF_WRAP_ARITH(n, T, U, W)					\
static inline T iec_add_##n(T a, T b)					\
{									\
	return (T)(U)(((W)(U)a + (W)(U)b) &			\
		      IEC__MASK(W, 8 * sizeof(U)));			\
}									\
static inline T iec_sub_##n(T a, T b)					\
{									\
	return (T)(U)(((W)(U)a - (W)(U)b) &			\
		      IEC__MASK(W, 8 * sizeof(U)));			\
}									\
static inline T iec_mul_##n(T a, T b)					\
{									\
	return (T)(U)(((W)(U)a * (W)(U)b) &			\
		      IEC__MASK(W, 8 * sizeof(U)));			\
}									\
static inline T iec_neg_##n(T a)					\
{									\
	return (T)(U)(((W)0 - (W)(U)a) &				\
		      IEC__MASK(W, 8 * sizeof(U)));			\
}

#define IEC__DEF_SIGNED_DIV(n, T)					\
static inline T iec_abs_##n(T a)					\
{									\
	return a < 0 ? iec_neg_##n(a) : a;				\
}									\
static inline T iec_div_##n(struct iec_ctx *ctx, T a, T b)		\
{									\
	if (iec_unlikely(b == 0)) {					\
		iec_fault_raise(ctx, IEC_FAULT_DIV_ZERO);		\
		return 0;						\
	}								\
	if (b == -1)							\
		return iec_neg_##n(a);					\
	return (T)(a / b);						\
}									\
static inline T iec_mod_##n(struct iec_ctx *ctx, T a, T b)		\
{									\
	if (iec_unlikely(b == 0)) {					\
		iec_fault_raise(ctx, IEC_FAULT_DIV_ZERO);		\
		return 0;						\
	}								\
	if (b == -1)							\
		return 0;						\
	return (T)(a % b);						\
}

#define IEC__DEF_UNSIGNED_DIV(n, T)					\
static inline T iec_abs_##n(T a)					\
{									\
	return a;							\
}									\
static inline T iec_div_##n(struct iec_ctx *ctx, T a, T b)		\
{									\
	if (iec_unlikely(b == 0)) {					\
		iec_fault_raise(ctx, IEC_FAULT_DIV_ZERO);		\
		return 0;						\
	}								\
	return (T)(a / b);						\
}									\
static inline T iec_mod_##n(struct iec_ctx *ctx, T a, T b)		\
{									\
	if (iec_unlikely(b == 0)) {					\
		iec_fault_raise(ctx, IEC_FAULT_DIV_ZERO);		\
		return 0;						\
	}								\
	return (T)(a % b);						\
}

/* SEL, MAX, MIN, LIMIT, MOVE and comparisons for a totally ordered type. */
#define IEC__DEF_SELECT_CMP(n, T)					\
static inline T iec_sel_##n(iec_bool g, T in0, T in1)			\
{									\
	return g ? in1 : in0;						\
}									\
static inline T iec_max_##n(T a, T b)					\
{									\
	return a >= b ? a : b;						\
}									\
static inline T iec_min_##n(T a, T b)					\
{									\
	return a <= b ? a : b;						\
}									\
static inline T iec_limit_##n(T mn, T in, T mx)				\
{									\
	return iec_min_##n(iec_max_##n(in, mn), mx);			\
}									\
static inline T iec_move_##n(T in)					\
{									\
	return in;							\
}									\
static inline iec_bool iec_gt_##n(T a, T b) { return a > b; }		\
static inline iec_bool iec_ge_##n(T a, T b) { return a >= b; }	\
static inline iec_bool iec_eq_##n(T a, T b) { return a == b; }	\
static inline iec_bool iec_le_##n(T a, T b) { return a <= b; }	\
static inline iec_bool iec_lt_##n(T a, T b) { return a < b; }		\
static inline iec_bool iec_ne_##n(T a, T b) { return a != b; }

/* Bit string functions; BITS is the width, W an unsigned type >= T. */
/*
 * All ones in the low BITS bits of W: results are masked before they are
 * narrowed to T (the same value; sparse warns about a cast that truncates
 * a constant once a shift or rotate of a constant is inlined).
 */
#define IEC__MASK(W, BITS)	((W)((((W)1 << ((BITS) - 1)) << 1) - 1))

#define IEC__DEF_BITS(n, T, W, BITS)					\
static inline T iec_and_##n(T a, T b) { return (T)(a & b); }		\
static inline T iec_or_##n(T a, T b) { return (T)(a | b); }		\
static inline T iec_xor_##n(T a, T b) { return (T)(a ^ b); }		\
static inline T iec_not_##n(T a) { return (T)(~(W)a & IEC__MASK(W, BITS)); } \
static inline T iec_shl_##n(T in, iec_s64 sh)				\
{									\
	if (sh < 0 || sh >= (BITS))					\
		return 0;						\
	return (T)(((W)in << sh) & IEC__MASK(W, BITS));			\
}									\
static inline T iec_shr_##n(T in, iec_s64 sh)				\
{									\
	if (sh < 0 || sh >= (BITS))					\
		return 0;						\
	return (T)((W)in >> sh);					\
}									\
static inline T iec_rol_##n(T in, iec_s64 sh)				\
{									\
	unsigned int r = (unsigned int)(((sh % (BITS)) + (BITS)) % (BITS)); \
									\
	if (r == 0)							\
		return in;						\
	return (T)((((W)in << r) | ((W)in >> ((BITS) - r))) &		\
		   IEC__MASK(W, BITS));						\
}									\
static inline T iec_ror_##n(T in, iec_s64 sh)				\
{									\
	unsigned int r = (unsigned int)(((sh % (BITS)) + (BITS)) % (BITS)); \
									\
	if (r == 0)							\
		return in;						\
	return (T)((((W)in >> r) | ((W)in << ((BITS) - r))) &		\
		   IEC__MASK(W, BITS));						\
}

IEC__DEF_WRAP_ARITH(sint, iec_sint, iec_u8, iec_u32)
IEC__DEF_WRAP_ARITH(int, iec_int, iec_u16, iec_u32)
IEC__DEF_WRAP_ARITH(dint, iec_dint, iec_u32, iec_u32)
IEC__DEF_WRAP_ARITH(lint, iec_lint, iec_u64, iec_u64)
IEC__DEF_WRAP_ARITH(usint, iec_usint, iec_u8, iec_u32)
IEC__DEF_WRAP_ARITH(uint, iec_uint, iec_u16, iec_u32)
IEC__DEF_WRAP_ARITH(udint, iec_udint, iec_u32, iec_u32)
IEC__DEF_WRAP_ARITH(ulint, iec_ulint, iec_u64, iec_u64)

IEC__DEF_SIGNED_DIV(sint, iec_sint)
IEC__DEF_SIGNED_DIV(int, iec_int)
IEC__DEF_SIGNED_DIV(dint, iec_dint)
IEC__DEF_SIGNED_DIV(lint, iec_lint)
IEC__DEF_UNSIGNED_DIV(usint, iec_usint)
IEC__DEF_UNSIGNED_DIV(uint, iec_uint)
IEC__DEF_UNSIGNED_DIV(udint, iec_udint)
IEC__DEF_UNSIGNED_DIV(ulint, iec_ulint)

IEC__DEF_SELECT_CMP(sint, iec_sint)
IEC__DEF_SELECT_CMP(int, iec_int)
IEC__DEF_SELECT_CMP(dint, iec_dint)
IEC__DEF_SELECT_CMP(lint, iec_lint)
IEC__DEF_SELECT_CMP(usint, iec_usint)
IEC__DEF_SELECT_CMP(uint, iec_uint)
IEC__DEF_SELECT_CMP(udint, iec_udint)
IEC__DEF_SELECT_CMP(ulint, iec_ulint)
IEC__DEF_SELECT_CMP(byte, iec_byte)
IEC__DEF_SELECT_CMP(word, iec_word)
IEC__DEF_SELECT_CMP(dword, iec_dword)
IEC__DEF_SELECT_CMP(lword, iec_lword)
IEC__DEF_SELECT_CMP(bool, iec_bool)
IEC__DEF_SELECT_CMP(char, iec_char)
IEC__DEF_SELECT_CMP(wchar, iec_wchar)
IEC__DEF_SELECT_CMP(time, iec_time)
IEC__DEF_SELECT_CMP(ltime, iec_ltime)
IEC__DEF_SELECT_CMP(date, iec_date)
IEC__DEF_SELECT_CMP(ldate, iec_ldate)
IEC__DEF_SELECT_CMP(tod, iec_tod)
IEC__DEF_SELECT_CMP(ltod, iec_ltod)
IEC__DEF_SELECT_CMP(dt, iec_dt)
IEC__DEF_SELECT_CMP(ldt, iec_ldt)

IEC__DEF_BITS(byte, iec_byte, iec_u32, 8)
IEC__DEF_BITS(word, iec_word, iec_u32, 16)
IEC__DEF_BITS(dword, iec_dword, iec_u32, 32)
IEC__DEF_BITS(lword, iec_lword, iec_u64, 64)

static inline iec_bool iec_and_bool(iec_bool a, iec_bool b) { return a && b; }
static inline iec_bool iec_or_bool(iec_bool a, iec_bool b) { return a || b; }
static inline iec_bool iec_xor_bool(iec_bool a, iec_bool b)
{
	return !a != !b;
}
static inline iec_bool iec_not_bool(iec_bool a) { return !a; }

/*
 * Comparisons of integers, BOOL, enumerations and times, as the generated
 * code writes them: the operands of one IEC type converted to 64 bits, so
 * that a comparison C finds always true or false (u <= 255 on a USINT,
 * w >= 0 on a UINT, x = x) compiles without -Wtype-limits or
 * -Wtautological-compare; inlined, the code is the plain comparison.
 */
#define IEC__CMP(name, op)						\
static inline iec_bool iec_##name##_s64(iec_s64 a, iec_s64 b)		\
{									\
	return a op b;							\
}									\
static inline iec_bool iec_##name##_u64(iec_u64 a, iec_u64 b)		\
{									\
	return a op b;							\
}
IEC__CMP(eq, ==)
IEC__CMP(ne, !=)
IEC__CMP(lt, <)
IEC__CMP(le, <=)
IEC__CMP(gt, >)
IEC__CMP(ge, >=)
#undef IEC__CMP

#endif /* IEC_INT_H */
