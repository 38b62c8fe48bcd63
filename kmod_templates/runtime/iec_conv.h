/* SPDX-License-Identifier: GPL-2.0-only OR MIT */
/*
 * iec_conv.h - type conversions that need no floating point.
 *
 * Names: iec_<from>_to_<to>, lower case, exactly as the standard's typed
 * conversion (INT_TO_REAL -> iec_int_to_real; BYTE_BCD_TO_USINT ->
 * iec_byte_bcd_to_usint).  Conversions involving REAL/LREAL are in
 * iec_real.h, those involving STRING/WSTRING in iec_string.h.
 *
 * Rules:
 *  - Between the integer, bit string and character types (SINT INT DINT
 *    LINT USINT UINT UDINT ULINT BYTE WORD DWORD LWORD CHAR WCHAR) the value
 *    is taken modulo 2^width of the destination (two's complement wrap,
 *    bit pattern kept): INT_TO_SINT(300) = 44, DINT_TO_UINT(-1) = 65535.
 *    Every pair exists, including T_TO_T (the identity).
 *  - <T>_TO_BOOL is (v <> 0); BOOL_TO_<T> is 0 or 1.
 *  - Time types and integers.  The integer counts
 *      TIME: milliseconds        LTIME: nanoseconds
 *      TOD:  ms since midnight   LTOD:  ns since midnight
 *      DATE: s since 1970-01-01  LDATE: ns since 1970-01-01
 *      DT:   s since 1970-01-01  LDT:   ns since 1970-01-01
 *    Durations (TIME) truncate toward zero, points in time (the others)
 *    round toward minus infinity; the count then wraps into the integer
 *    type.  Integer to time multiplies (wrapping); a DATE is floored to a
 *    whole day and a TOD is reduced modulo 24 h.
 *  - TIME_TO_LTIME, DT_TO_DATE, DT_TO_TOD, LDT_TO_DT ... between time types.
 *  - BCD: BYTE_BCD_TO_USINT, WORD_BCD_TO_UINT, DWORD_BCD_TO_UDINT,
 *    LWORD_BCD_TO_ULINT decode packed BCD; a nibble above 9 makes the
 *    result 0.  USINT_TO_BCD_BYTE ... ULINT_TO_BCD_LWORD encode; a value
 *    with more decimal digits than fit (USINT 100 in a BYTE) gives 0.
 */
#ifndef IEC_CONV_H
#define IEC_CONV_H

#include "iec_int.h"
#include "iec_time.h"

/* name, C type, unsigned C type of the same width */
#define IEC__INT_LIST_A(X)						\
	X(sint, iec_sint, iec_u8)					\
	X(int, iec_int, iec_u16)					\
	X(dint, iec_dint, iec_u32)					\
	X(lint, iec_lint, iec_u64)					\
	X(usint, iec_usint, iec_u8)					\
	X(uint, iec_uint, iec_u16)					\
	X(udint, iec_udint, iec_u32)					\
	X(ulint, iec_ulint, iec_u64)					\
	X(byte, iec_byte, iec_u8)					\
	X(word, iec_word, iec_u16)					\
	X(dword, iec_dword, iec_u32)					\
	X(lword, iec_lword, iec_u64)					\
	X(char, iec_char, iec_u8)					\
	X(wchar, iec_wchar, iec_u16)

#define IEC__INT_LIST_B(X, fn, fT)					\
	X(fn, fT, sint, iec_sint, iec_u8)				\
	X(fn, fT, int, iec_int, iec_u16)				\
	X(fn, fT, dint, iec_dint, iec_u32)				\
	X(fn, fT, lint, iec_lint, iec_u64)				\
	X(fn, fT, usint, iec_usint, iec_u8)				\
	X(fn, fT, uint, iec_uint, iec_u16)				\
	X(fn, fT, udint, iec_udint, iec_u32)				\
	X(fn, fT, ulint, iec_ulint, iec_u64)				\
	X(fn, fT, byte, iec_byte, iec_u8)				\
	X(fn, fT, word, iec_word, iec_u16)				\
	X(fn, fT, dword, iec_dword, iec_u32)				\
	X(fn, fT, lword, iec_lword, iec_u64)				\
	X(fn, fT, char, iec_char, iec_u8)				\
	X(fn, fT, wchar, iec_wchar, iec_u16)

/* The low bits of v (modulo 2^n, then the target's two's complement).  v
 * is masked in 64 bits to the target's width before it is narrowed: sparse
 * warns "cast truncates bits from constant value" on a narrowing cast once
 * a call with a constant is inlined (as for iec_int.h's arithmetic). */
#define IEC__DEF_CONV_INT(fn, fT, tn, tT, tU)				\
static inline tT iec_##fn##_to_##tn(fT v)				\
{									\
	return (tT)(tU)((iec_u64)v &					\
			IEC__MASK(iec_u64, 8 * sizeof(tU)));		\
}

#define IEC__CONV_FROM(fn, fT, fU) IEC__INT_LIST_B(IEC__DEF_CONV_INT, fn, fT)

IEC__INT_LIST_A(IEC__CONV_FROM)

/* BOOL <-> integers */
#define IEC__DEF_CONV_BOOL(n, T, U)					\
static inline iec_bool iec_##n##_to_bool(T v)				\
{									\
	return v != 0;							\
}									\
static inline T iec_bool_to_##n(iec_bool b)				\
{									\
	return (T)(b ? 1 : 0);						\
}

IEC__INT_LIST_A(IEC__DEF_CONV_BOOL)

static inline iec_bool iec_bool_to_bool(iec_bool b)
{
	return b ? 1 : 0;
}

/* Time types <-> integers.  kind: 0 duration, 1 point, 2 date, 3 tod. */
static inline iec_s64 iec__time_to_count(iec_s64 v, iec_s64 unit, int kind)
{
	return kind == 0 ? v / unit : iec__floordiv(v, unit);
}

static inline iec_s64 iec__count_to_time(iec_s64 n, iec_s64 unit, int kind)
{
	iec_s64 v = iec__wrap_mul(n, unit);

	if (kind == 2)
		return iec__wrap_sub(v, iec__floormod(v, IEC_NS_PER_DAY));
	if (kind == 3)
		return iec__floormod(v, IEC_NS_PER_DAY);
	return v;
}

#define IEC__TIME_LIST(X, ...)						\
	X(time, iec_time, IEC_NS_PER_MS, 0, __VA_ARGS__)		\
	X(ltime, iec_ltime, 1, 0, __VA_ARGS__)				\
	X(tod, iec_tod, IEC_NS_PER_MS, 3, __VA_ARGS__)			\
	X(ltod, iec_ltod, 1, 3, __VA_ARGS__)				\
	X(date, iec_date, IEC_NS_PER_S, 2, __VA_ARGS__)			\
	X(ldate, iec_ldate, 1, 2, __VA_ARGS__)				\
	X(dt, iec_dt, IEC_NS_PER_S, 1, __VA_ARGS__)			\
	X(ldt, iec_ldt, 1, 1, __VA_ARGS__)

#define IEC__DEF_CONV_TIME_INT(tn, tT, unit, kind, in, iT, iU)		\
static inline iT iec_##tn##_to_##in(tT v)				\
{									\
	return (iT)(iU)iec__time_to_count(v, unit, kind);		\
}									\
static inline tT iec_##in##_to_##tn(iT v)				\
{									\
	return iec__count_to_time((iec_s64)(iec_u64)v, unit, kind);	\
}

#define IEC__CONV_TIME_FOR(in, iT, iU)					\
	IEC__TIME_LIST(IEC__DEF_CONV_TIME_INT, in, iT, iU)

IEC__INT_LIST_A(IEC__CONV_TIME_FOR)

/* Between time types. */
static inline iec_ltime iec_time_to_ltime(iec_time v) { return v; }
static inline iec_time iec_ltime_to_time(iec_ltime v) { return v; }
static inline iec_ltod iec_tod_to_ltod(iec_tod v) { return v; }
static inline iec_tod iec_ltod_to_tod(iec_ltod v) { return v; }
static inline iec_ldate iec_date_to_ldate(iec_date v) { return v; }
static inline iec_date iec_ldate_to_date(iec_ldate v) { return v; }
static inline iec_ldt iec_dt_to_ldt(iec_dt v) { return v; }
static inline iec_dt iec_ldt_to_dt(iec_ldt v) { return v; }

static inline iec_date iec_dt_to_date(iec_dt v)
{
	return iec__wrap_sub(v, iec__floormod(v, IEC_NS_PER_DAY));
}

static inline iec_tod iec_dt_to_tod(iec_dt v)
{
	return iec__floormod(v, IEC_NS_PER_DAY);
}

static inline iec_ldate iec_ldt_to_ldate(iec_ldt v)
{
	return iec_dt_to_date(v);
}

static inline iec_ltod iec_ldt_to_ltod(iec_ldt v) { return iec_dt_to_tod(v); }
static inline iec_date iec_ldt_to_date(iec_ldt v) { return iec_dt_to_date(v); }
static inline iec_tod iec_ldt_to_tod(iec_ldt v) { return iec_dt_to_tod(v); }

/* BCD */
static inline iec_u64 iec__bcd_decode(iec_u64 v, int digits)
{
	iec_u64 r = 0, scale = 1;
	int i;

	for (i = 0; i < digits; i++) {
		unsigned int nib = (unsigned int)(v >> (4 * i)) & 0xf;

		if (nib > 9)
			return 0;
		r += nib * scale;
		scale *= 10;
	}
	return r;
}

static inline iec_u64 iec__bcd_encode(iec_u64 v, int digits)
{
	iec_u64 r = 0;
	int i;

	for (i = 0; i < digits; i++) {
		r |= (v % 10) << (4 * i);
		v /= 10;
	}
	return v ? 0 : r;
}

/* the overloaded *_TO_BCD of a signed integer: a negative value gives 0 */
static inline iec_u64 iec__bcd_encode_s(iec_s64 v, int digits)
{
	return v < 0 ? 0 : iec__bcd_encode((iec_u64)v, digits);
}

static inline iec_usint iec_byte_bcd_to_usint(iec_byte v)
{
	return (iec_usint)iec__bcd_decode(v, 2);
}

static inline iec_uint iec_word_bcd_to_uint(iec_word v)
{
	return (iec_uint)iec__bcd_decode(v, 4);
}

static inline iec_udint iec_dword_bcd_to_udint(iec_dword v)
{
	return (iec_udint)iec__bcd_decode(v, 8);
}

static inline iec_ulint iec_lword_bcd_to_ulint(iec_lword v)
{
	return iec__bcd_decode(v, 16);
}

static inline iec_byte iec_usint_to_bcd_byte(iec_usint v)
{
	return (iec_byte)iec__bcd_encode(v, 2);
}

static inline iec_word iec_uint_to_bcd_word(iec_uint v)
{
	return (iec_word)iec__bcd_encode(v, 4);
}

static inline iec_dword iec_udint_to_bcd_dword(iec_udint v)
{
	return (iec_dword)iec__bcd_encode(v, 8);
}

static inline iec_lword iec_ulint_to_bcd_lword(iec_ulint v)
{
	return iec__bcd_encode(v, 16);
}

#endif /* IEC_CONV_H */
