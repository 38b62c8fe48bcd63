/* SPDX-License-Identifier: GPL-2.0-only OR MIT */
/*
 * iec_time.h - TIME, DATE, TIME_OF_DAY and DATE_AND_TIME arithmetic.
 *
 * All of these are signed 64-bit nanosecond counts (see iec_types.h).
 * Names follow the standard's typed functions, lower case:
 *   ADD_TIME -> iec_add_time, SUB_DT_DT -> iec_sub_dt_dt, ...
 * The L* forms (ADD_LTIME, ADD_LTOD_LTIME, ...) are the same functions under
 * their own names.
 *
 * Semantics:
 *  - TIME arithmetic wraps around in two's complement (never undefined).
 *  - MUL_TIME(T, N) multiplies by an integer; DIV_TIME(T, N) truncates
 *    toward zero, N = 0 records IEC_FAULT_DIV_ZERO and returns T#0s.
 *    The LREAL forms (iec_mul_time_lreal, iec_div_time_lreal) are in
 *    iec_real.h.
 *  - ADD_TOD_TIME and SUB_TOD_TIME wrap modulo 24 h, so the result is
 *    always a valid TIME_OF_DAY (TOD#23:00 + T#2h = TOD#01:00).
 *  - SUB_TOD_TOD, SUB_DATE_DATE, SUB_DT_DT are plain differences (TIME,
 *    possibly negative).
 *  - Calendar: proleptic Gregorian, DATE#1970-01-01 = 0.  A signed 64-bit
 *    nanosecond count spans DT#1677-09-21-00:12:43.145224192 ..
 *    DT#2262-04-11-23:47:16.854775807; dates outside that range wrap
 *    around (defined, never undefined behaviour).
 */
#ifndef IEC_TIME_H
#define IEC_TIME_H

#include "iec_fault.h"

/* Floor division and modulo by a positive divisor. */
static inline iec_s64 iec__floordiv(iec_s64 a, iec_s64 b)
{
	iec_s64 q = a / b;

	return (a % b < 0) ? q - 1 : q;
}

static inline iec_s64 iec__floormod(iec_s64 a, iec_s64 b)
{
	iec_s64 r = a % b;

	return r < 0 ? r + b : r;
}

static inline iec_s64 iec__wrap_add(iec_s64 a, iec_s64 b)
{
	return (iec_s64)((iec_u64)a + (iec_u64)b);
}

static inline iec_s64 iec__wrap_sub(iec_s64 a, iec_s64 b)
{
	return (iec_s64)((iec_u64)a - (iec_u64)b);
}

static inline iec_s64 iec__wrap_mul(iec_s64 a, iec_s64 b)
{
	return (iec_s64)((iec_u64)a * (iec_u64)b);
}

static inline iec_time iec_add_time(iec_time a, iec_time b)
{
	return iec__wrap_add(a, b);
}

static inline iec_time iec_sub_time(iec_time a, iec_time b)
{
	return iec__wrap_sub(a, b);
}

static inline iec_time iec_mul_time(iec_time t, iec_lint n)
{
	return iec__wrap_mul(t, n);
}

static inline iec_time iec_div_time(struct iec_ctx *ctx, iec_time t,
				    iec_lint n)
{
	if (iec_unlikely(n == 0)) {
		iec_fault_raise(ctx, IEC_FAULT_DIV_ZERO);
		return 0;
	}
	if (n == -1)
		return iec__wrap_sub(0, t);
	return t / n;
}

static inline iec_ltime iec_add_ltime(iec_ltime a, iec_ltime b)
{
	return iec_add_time(a, b);
}

static inline iec_ltime iec_sub_ltime(iec_ltime a, iec_ltime b)
{
	return iec_sub_time(a, b);
}

static inline iec_ltime iec_mul_ltime(iec_ltime t, iec_lint n)
{
	return iec_mul_time(t, n);
}

static inline iec_ltime iec_div_ltime(struct iec_ctx *ctx, iec_ltime t,
				      iec_lint n)
{
	return iec_div_time(ctx, t, n);
}

static inline iec_tod iec_add_tod_time(iec_tod tod, iec_time t)
{
	return iec__floormod(iec__floormod(tod, IEC_NS_PER_DAY) +
			     iec__floormod(t, IEC_NS_PER_DAY), IEC_NS_PER_DAY);
}

static inline iec_tod iec_sub_tod_time(iec_tod tod, iec_time t)
{
	return iec__floormod(iec__floormod(tod, IEC_NS_PER_DAY) -
			     iec__floormod(t, IEC_NS_PER_DAY), IEC_NS_PER_DAY);
}

static inline iec_time iec_sub_tod_tod(iec_tod a, iec_tod b)
{
	return iec__wrap_sub(a, b);
}

static inline iec_dt iec_add_dt_time(iec_dt dt, iec_time t)
{
	return iec__wrap_add(dt, t);
}

static inline iec_dt iec_sub_dt_time(iec_dt dt, iec_time t)
{
	return iec__wrap_sub(dt, t);
}

static inline iec_time iec_sub_dt_dt(iec_dt a, iec_dt b)
{
	return iec__wrap_sub(a, b);
}

static inline iec_time iec_sub_date_date(iec_date a, iec_date b)
{
	return iec__wrap_sub(a, b);
}

static inline iec_dt iec_concat_date_tod(iec_date d, iec_tod tod)
{
	return iec__wrap_add(d, tod);
}

static inline iec_ltod iec_add_ltod_ltime(iec_ltod tod, iec_ltime t)
{
	return iec_add_tod_time(tod, t);
}

static inline iec_ltod iec_sub_ltod_ltime(iec_ltod tod, iec_ltime t)
{
	return iec_sub_tod_time(tod, t);
}

static inline iec_ltime iec_sub_ltod_ltod(iec_ltod a, iec_ltod b)
{
	return iec_sub_tod_tod(a, b);
}

static inline iec_ldt iec_add_ldt_ltime(iec_ldt dt, iec_ltime t)
{
	return iec_add_dt_time(dt, t);
}

static inline iec_ldt iec_sub_ldt_ltime(iec_ldt dt, iec_ltime t)
{
	return iec_sub_dt_time(dt, t);
}

static inline iec_ltime iec_sub_ldt_ldt(iec_ldt a, iec_ldt b)
{
	return iec_sub_dt_dt(a, b);
}

static inline iec_ltime iec_sub_ldate_ldate(iec_ldate a, iec_ldate b)
{
	return iec_sub_date_date(a, b);
}

static inline iec_ldt iec_concat_ldate_ltod(iec_ldate d, iec_ltod tod)
{
	return iec_concat_date_tod(d, tod);
}

/*
 * Calendar helpers (days since 1970-01-01 <-> year/month/day), after
 * H. Hinnant's public-domain "chrono-compatible low-level date algorithms".
 */
static inline iec_s64 iec__days_from_civil(iec_s64 y, iec_s64 m, iec_s64 d)
{
	iec_s64 era, yoe, doy, doe;

	y -= m <= 2;
	era = iec__floordiv(y, 400);
	yoe = y - era * 400;
	doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
	doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
	return era * 146097 + doe - 719468;
}

static inline void iec__civil_from_days(iec_s64 z, iec_s64 *y, iec_s64 *m,
					iec_s64 *d)
{
	iec_s64 era, doe, yoe, doy, mp;

	z += 719468;
	era = iec__floordiv(z, 146097);
	doe = z - era * 146097;
	yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
	doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
	mp = (5 * doy + 2) / 153;
	*d = doy - (153 * mp + 2) / 5 + 1;
	*m = mp < 10 ? mp + 3 : mp - 9;
	*y = yoe + era * 400 + (*m <= 2);
}

/*
 * CONCAT_DATE(YEAR, MONTH, DAY), CONCAT_TOD(HOUR, MINUTE, SECOND, MS),
 * CONCAT_DT(...).  Arguments are not range checked: out-of-range fields
 * carry over (month 13 = January of the next year), as the arithmetic
 * naturally does; years are clamped to -9999..9999 and the other fields
 * to +-1000000 so no intermediate value can overflow.
 */
static inline iec_s64 iec__clamp_year(iec_s64 y)
{
	return y < -9999 ? -9999 : (y > 9999 ? 9999 : y);
}

static inline iec_s64 iec__clamp_small(iec_s64 v)
{
	return v < -1000000 ? -1000000 : (v > 1000000 ? 1000000 : v);
}

static inline iec_date iec_concat_date(iec_lint year, iec_lint month,
				       iec_lint day)
{
	iec_s64 y = iec__clamp_year(year);
	iec_s64 m0 = iec__clamp_small(month) - 1;

	y += iec__floordiv(m0, 12);
	m0 = iec__floormod(m0, 12);
	return iec__wrap_mul(iec__days_from_civil(y, m0 + 1, 1) +
			     iec__clamp_small(day) - 1, IEC_NS_PER_DAY);
}

static inline iec_tod iec_concat_tod(iec_lint hour, iec_lint minute,
				     iec_lint second, iec_lint ms)
{
	iec_s64 ns = iec__clamp_small(hour) * IEC_NS_PER_H +
		     iec__clamp_small(minute) * IEC_NS_PER_MIN +
		     iec__clamp_small(second) * IEC_NS_PER_S +
		     iec__clamp_small(ms) * IEC_NS_PER_MS;

	return iec__floormod(ns, IEC_NS_PER_DAY);
}

static inline iec_dt iec_concat_dt(iec_lint year, iec_lint month,
				   iec_lint day, iec_lint hour,
				   iec_lint minute, iec_lint second,
				   iec_lint ms)
{
	return iec_concat_date_tod(iec_concat_date(year, month, day),
				   iec_concat_tod(hour, minute, second, ms));
}

static inline void iec_split_date(iec_date d, iec_lint *year,
				  iec_lint *month, iec_lint *day)
{
	iec__civil_from_days(iec__floordiv(d, IEC_NS_PER_DAY), year, month,
			     day);
}

static inline void iec_split_tod(iec_tod tod, iec_lint *hour,
				 iec_lint *minute, iec_lint *second,
				 iec_lint *ms)
{
	iec_s64 ns = iec__floormod(tod, IEC_NS_PER_DAY);

	*hour = ns / IEC_NS_PER_H;
	*minute = ns / IEC_NS_PER_MIN % 60;
	*second = ns / IEC_NS_PER_S % 60;
	*ms = ns / IEC_NS_PER_MS % 1000;
}

static inline void iec_split_dt(iec_dt dt, iec_lint *year, iec_lint *month,
				iec_lint *day, iec_lint *hour,
				iec_lint *minute, iec_lint *second,
				iec_lint *ms)
{
	iec_split_date(dt, year, month, day);
	iec_split_tod(dt, hour, minute, second, ms);
}

/* DAY_OF_WEEK: 0 = Sunday .. 6 = Saturday (1970-01-01 was a Thursday). */
static inline iec_lint iec_day_of_week(iec_date d)
{
	return iec__floormod(iec__floordiv(d, IEC_NS_PER_DAY) + 4, 7);
}

#endif /* IEC_TIME_H */
