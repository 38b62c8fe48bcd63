/* SPDX-License-Identifier: GPL-2.0-only OR MIT */
/*
 * iec_types.h - IEC 61131-3 elementary data types as C types.
 *
 * Scalars (C name = "iec_" + lower-case IEC name):
 *
 *   BOOL                      iec_bool    uint8, only 0 or 1 is ever stored
 *   SINT INT DINT LINT        iec_sint .. iec_lint     int8/16/32/64
 *   USINT UINT UDINT ULINT    iec_usint .. iec_ulint   uint8/16/32/64
 *   BYTE WORD DWORD LWORD     iec_byte .. iec_lword    uint8/16/32/64
 *   REAL LREAL                iec_real (float), iec_lreal (double)
 *   CHAR WCHAR                iec_char (uint8), iec_wchar (uint16)
 *   TIME LTIME                iec_time, iec_ltime: signed 64-bit nanoseconds
 *   DATE LDATE                iec_date, iec_ldate: ns since 1970-01-01,
 *                             always a multiple of one day
 *   TIME_OF_DAY LTOD          iec_tod, iec_ltod: ns since midnight,
 *                             0 <= v < 86400 s
 *   DATE_AND_TIME LDT         iec_dt, iec_ldt: ns since 1970-01-01-00:00:00
 *
 * Long and short time types share one representation, so the L* variants
 * are the same C type and their conversions are identities.
 *
 * Strings.  STRING[n] (1 <= n <= IEC_STRING_MAX_CAP) is laid out as
 *
 *   struct iec_string_<n> {
 *           iec_u16 len;          current length, 0 <= len <= n
 *           char data[n + 1];     the characters; data[len] is kept 0
 *   };
 *
 * so a variable is 2 + n + 1 bytes (plus padding to an even size).  The
 * default STRING (n = IEC_STRING_DEFAULT_LEN = 254) is predeclared as
 * struct iec_string; declare other lengths once per translation unit with
 * IEC_DECLARE_STRING(n).  WSTRING[n] is the same with iec_u16 characters
 * (UCS-2): struct iec_wstring_<n> / struct iec_wstring, and
 * IEC_DECLARE_WSTRING(n).  Assignments and every string function truncate
 * the result to the destination's capacity n; nothing is written past
 * data[n].
 *
 * Runtime functions never see the structs: they take by-value views.
 *   IEC_SV(var)   read-only view {pointer, length} of a STRING variable
 *   IEC_SB(var)   destination {pointer, &len, capacity} of a STRING variable
 *   IEC_SLIT("x") view of a C string literal (the IEC literal, unescaped;
 *                 embedded NULs are allowed)
 *   IEC_WSV, IEC_WSB, IEC_WSLIT(u"x") are the WSTRING equivalents.
 * IEC_SV clamps the length to the capacity, so a corrupted len can never
 * make a function read past the buffer.
 */
#ifndef IEC_TYPES_H
#define IEC_TYPES_H

#include "iec_platform.h"

typedef iec_u8 iec_bool;

typedef iec_s8 iec_sint;
typedef iec_s16 iec_int;
typedef iec_s32 iec_dint;
typedef iec_s64 iec_lint;
typedef iec_u8 iec_usint;
typedef iec_u16 iec_uint;
typedef iec_u32 iec_udint;
typedef iec_u64 iec_ulint;

typedef iec_u8 iec_byte;
typedef iec_u16 iec_word;
typedef iec_u32 iec_dword;
typedef iec_u64 iec_lword;

typedef float iec_real;
typedef double iec_lreal;

typedef iec_u8 iec_char;
typedef iec_u16 iec_wchar;

typedef iec_s64 iec_time;
typedef iec_s64 iec_ltime;
typedef iec_s64 iec_date;
typedef iec_s64 iec_ldate;
typedef iec_s64 iec_tod;
typedef iec_s64 iec_ltod;
typedef iec_s64 iec_dt;
typedef iec_s64 iec_ldt;

/* Time units in nanoseconds. */
#define IEC_NS_PER_US	1000LL
#define IEC_NS_PER_MS	1000000LL
#define IEC_NS_PER_S	1000000000LL
#define IEC_NS_PER_MIN	(60LL * IEC_NS_PER_S)
#define IEC_NS_PER_H	(3600LL * IEC_NS_PER_S)
#define IEC_NS_PER_DAY	(86400LL * IEC_NS_PER_S)

#define IEC_STRING_DEFAULT_LEN	254
#define IEC_STRING_MAX_CAP	65534

#define IEC_DECLARE_STRING(n)				\
	struct iec_string_##n {				\
		iec_u16 len;				\
		char data[(n) + 1];			\
	}

#define IEC_DECLARE_WSTRING(n)				\
	struct iec_wstring_##n {			\
		iec_u16 len;				\
		iec_u16 data[(n) + 1];			\
	}

/* STRING and WSTRING without a length: n = 254. */
struct iec_string {
	iec_u16 len;
	char data[IEC_STRING_DEFAULT_LEN + 1];
};

struct iec_wstring {
	iec_u16 len;
	iec_u16 data[IEC_STRING_DEFAULT_LEN + 1];
};

/* Read-only view of a string operand. */
struct iec_strv {
	const char *p;
	iec_u16 len;
};

/* Destination of a string result. */
struct iec_strbuf {
	char *p;
	iec_u16 *len;
	iec_u16 cap;
};

struct iec_wstrv {
	const iec_u16 *p;
	iec_u16 len;
};

struct iec_wstrbuf {
	iec_u16 *p;
	iec_u16 *len;
	iec_u16 cap;
};

static inline struct iec_strv iec_strv_make(const char *p, iec_u16 len,
					    iec_u16 cap)
{
	struct iec_strv v = { .p = p, .len = len <= cap ? len : cap };

	return v;
}

static inline struct iec_wstrv iec_wstrv_make(const iec_u16 *p, iec_u16 len,
					      iec_u16 cap)
{
	struct iec_wstrv v = { .p = p, .len = len <= cap ? len : cap };

	return v;
}

#define IEC_STR_CAP(s)	((iec_u16)(sizeof((s).data) / sizeof((s).data[0]) - 1))

#define IEC_SV(s)	iec_strv_make((s).data, (s).len, IEC_STR_CAP(s))
#define IEC_SB(s)	((struct iec_strbuf){ .p = (s).data, .len = &(s).len, \
					      .cap = IEC_STR_CAP(s) })
#define IEC_SLIT(lit)	((struct iec_strv){ .p = (lit), \
					    .len = (iec_u16)(sizeof(lit) - 1) })

#define IEC_WSV(s)	iec_wstrv_make((s).data, (s).len, IEC_STR_CAP(s))
#define IEC_WSB(s)	((struct iec_wstrbuf){ .p = (s).data, \
					       .len = &(s).len, \
					       .cap = IEC_STR_CAP(s) })
#define IEC_WSLIT(lit)	((struct iec_wstrv){ .p = (const iec_u16 *)(lit), \
					     .len = (iec_u16)(sizeof(lit) / 2 - 1) })

#endif /* IEC_TYPES_H */
