/* SPDX-License-Identifier: GPL-2.0-only OR MIT */
/*
 * iec_string.h - STRING and WSTRING functions and conversions.
 *
 * Layout and views: see iec_types.h.  Operands are passed as views
 * (struct iec_strv, built with IEC_SV(var) or IEC_SLIT("lit")), results go
 * to a destination (struct iec_strbuf, IEC_SB(var)) given first:
 *
 *   s := CONCAT(a, 'xy');  ->  iec_concat_string(IEC_SB(s), IEC_SV(a),
 *                                                IEC_SLIT("xy"));
 *   n := LEN(s);           ->  n = (iec_int)iec_len_string(IEC_SV(s));
 *   s := t;                ->  iec_assign_string(IEC_SB(s), IEC_SV(t));
 *
 * WSTRING: the same names with _wstring, views IEC_WSV/IEC_WSLIT and
 * destinations IEC_WSB.  The extensible CONCAT is emitted as a chain of
 * two-operand calls into the destination (the destination may be an
 * operand: every function reads all operands before it overwrites them,
 * so s := CONCAT(s, s) or s := INSERT(s, s, 2) are correct).
 *
 * Positions are 1-based, lengths and positions are LINT; the result never
 * exceeds the destination capacity (it is truncated) and nothing is written
 * past data[cap].  Defined outcomes for odd arguments (no fault raised):
 *   LEFT/RIGHT(IN, L):   L <= 0 gives '', L >= LEN(IN) gives IN.
 *   MID(IN, L, P):       P < 1 or P > LEN(IN) gives ''; L is clamped to
 *                        the characters available from P.
 *   INSERT(IN1, IN2, P): IN2 after the first P characters; P <= 0 inserts
 *                        at the front, P >= LEN(IN1) appends.
 *   DELETE(IN, L, P):    P < 1 or P > LEN(IN) gives IN unchanged; L is
 *                        clamped; L <= 0 deletes nothing.
 *   REPLACE(IN1, IN2, L, P): P is clamped to 1..LEN(IN1)+1, L to 0..what is
 *                        left; then IN1[P..P+L-1] is replaced by IN2.
 *   FIND(IN1, IN2):      position of the first IN2 in IN1, 0 if absent or
 *                        if IN2 is empty.  Costs at most LEN(IN1)*LEN(IN2)
 *                        character comparisons.
 *   LEN returns DINT, FIND returns DINT; the compiler converts.
 * Comparisons (GT GE EQ LE LT NE) are lexicographic on the character codes;
 * a proper prefix is smaller.
 *
 * Conversions (names iec_<type>_to_string / iec_string_to_<type>, and
 * _wstring):
 *   integers and bit strings -> decimal ('-123', BYTE 16#FF -> '255');
 *   BOOL -> 'TRUE' / 'FALSE';
 *   TIME -> 'T#1d2h3m4s5ms6us7ns' (zero parts omitted, 'T#0s'), LTIME ->
 *   'LTIME#...'; DATE -> 'D#2024-01-31'; TOD -> 'TOD#12:34:56.789'; DT ->
 *   'DT#2024-01-31-12:34:56.789' (the fraction is printed only when not
 *   zero, trailing zeros dropped); LDATE/LTOD/LDT use LDATE#/LTOD#/LDT#;
 *   CHAR -> a one-character string.
 * String -> value accepts leading and trailing blanks, a sign, '_' between
 * digits and base prefixes 2#, 8#, 16#; a typed prefix (INT#, T#, TIME#,
 * D#, DATE#, TOD#, TIME_OF_DAY#, DT#, DATE_AND_TIME#, and the L forms) is
 * skipped.  Integers saturate to the range of the type.  A string that is
 * not a valid literal converts to 0 (FALSE, T#0s, D#1970-01-01, '' for
 * CHAR: 0); no fault is raised.  STRING_TO_BOOL takes TRUE/FALSE (any case)
 * or an integer (non-zero = TRUE).  WSTRING <-> STRING maps characters
 * 0..255 one to one and any other WSTRING character to '?'.
 */
#ifndef IEC_STRING_H
#define IEC_STRING_H

#include "iec_types.h"

static inline iec_dint iec_len_string(struct iec_strv s)
{
	return s.len;
}

static inline iec_dint iec_len_wstring(struct iec_wstrv s)
{
	return s.len;
}

void iec_assign_string(struct iec_strbuf dst, struct iec_strv src);
void iec_left_string(struct iec_strbuf dst, struct iec_strv in, iec_lint l);
void iec_right_string(struct iec_strbuf dst, struct iec_strv in, iec_lint l);
void iec_mid_string(struct iec_strbuf dst, struct iec_strv in, iec_lint l,
		    iec_lint p);
void iec_concat_string(struct iec_strbuf dst, struct iec_strv in1,
		       struct iec_strv in2);
void iec_insert_string(struct iec_strbuf dst, struct iec_strv in1,
		       struct iec_strv in2, iec_lint p);
void iec_delete_string(struct iec_strbuf dst, struct iec_strv in, iec_lint l,
		       iec_lint p);
void iec_replace_string(struct iec_strbuf dst, struct iec_strv in1,
			struct iec_strv in2, iec_lint l, iec_lint p);
iec_dint iec_find_string(struct iec_strv in1, struct iec_strv in2);
int iec_cmp_string(struct iec_strv a, struct iec_strv b);

void iec_assign_wstring(struct iec_wstrbuf dst, struct iec_wstrv src);
void iec_left_wstring(struct iec_wstrbuf dst, struct iec_wstrv in,
		      iec_lint l);
void iec_right_wstring(struct iec_wstrbuf dst, struct iec_wstrv in,
		       iec_lint l);
void iec_mid_wstring(struct iec_wstrbuf dst, struct iec_wstrv in, iec_lint l,
		     iec_lint p);
void iec_concat_wstring(struct iec_wstrbuf dst, struct iec_wstrv in1,
			struct iec_wstrv in2);
void iec_insert_wstring(struct iec_wstrbuf dst, struct iec_wstrv in1,
			struct iec_wstrv in2, iec_lint p);
void iec_delete_wstring(struct iec_wstrbuf dst, struct iec_wstrv in,
			iec_lint l, iec_lint p);
void iec_replace_wstring(struct iec_wstrbuf dst, struct iec_wstrv in1,
			 struct iec_wstrv in2, iec_lint l, iec_lint p);
iec_dint iec_find_wstring(struct iec_wstrv in1, struct iec_wstrv in2);
int iec_cmp_wstring(struct iec_wstrv a, struct iec_wstrv b);

#define IEC__DEF_STR_CMP(n, V)						\
static inline iec_bool iec_gt_##n(V a, V b) { return iec_cmp_##n(a, b) > 0; } \
static inline iec_bool iec_ge_##n(V a, V b) { return iec_cmp_##n(a, b) >= 0; } \
static inline iec_bool iec_eq_##n(V a, V b) { return iec_cmp_##n(a, b) == 0; } \
static inline iec_bool iec_le_##n(V a, V b) { return iec_cmp_##n(a, b) <= 0; } \
static inline iec_bool iec_lt_##n(V a, V b) { return iec_cmp_##n(a, b) < 0; } \
static inline iec_bool iec_ne_##n(V a, V b) { return iec_cmp_##n(a, b) != 0; }

IEC__DEF_STR_CMP(string, struct iec_strv)
IEC__DEF_STR_CMP(wstring, struct iec_wstrv)

void iec_string_to_wstring(struct iec_wstrbuf dst, struct iec_strv src);
void iec_wstring_to_string(struct iec_strbuf dst, struct iec_wstrv src);
void iec_char_to_string(struct iec_strbuf dst, iec_char c);
void iec_wchar_to_wstring(struct iec_wstrbuf dst, iec_wchar c);
iec_char iec_string_to_char(struct iec_strv s);
iec_wchar iec_wstring_to_wchar(struct iec_wstrv s);

/* <type>_TO_STRING, STRING_TO_<type>, and the WSTRING forms. */
#define IEC__STR_CONV_LIST(X)						\
	X(bool, iec_bool)						\
	X(sint, iec_sint)						\
	X(int, iec_int)							\
	X(dint, iec_dint)						\
	X(lint, iec_lint)						\
	X(usint, iec_usint)						\
	X(uint, iec_uint)						\
	X(udint, iec_udint)						\
	X(ulint, iec_ulint)						\
	X(byte, iec_byte)						\
	X(word, iec_word)						\
	X(dword, iec_dword)						\
	X(lword, iec_lword)						\
	X(time, iec_time)						\
	X(ltime, iec_ltime)						\
	X(date, iec_date)						\
	X(ldate, iec_ldate)						\
	X(tod, iec_tod)							\
	X(ltod, iec_ltod)						\
	X(dt, iec_dt)							\
	X(ldt, iec_ldt)

#define IEC__DECL_STR_CONV(n, T)					\
void iec_##n##_to_string(struct iec_strbuf dst, T v);			\
T iec_string_to_##n(struct iec_strv s);					\
void iec_##n##_to_wstring(struct iec_wstrbuf dst, T v);			\
T iec_wstring_to_##n(struct iec_wstrv s);

IEC__STR_CONV_LIST(IEC__DECL_STR_CONV)

/*
 * Internal helpers shared with iec_real.c (not for generated code):
 * format into a char buffer and store it in a destination, and a generic
 * character reader for STRING (esz 1) and WSTRING (esz 2) views.
 */
void iec__store_chars(struct iec_strbuf dst, const char *p, unsigned int n);
void iec__store_wchars(struct iec_wstrbuf dst, const char *p,
		       unsigned int n);
unsigned int iec__narrow(char *buf, unsigned int size, const iec_u16 *p,
			 unsigned int len);

#endif /* IEC_STRING_H */
