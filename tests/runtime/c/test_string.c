/* SPDX-License-Identifier: GPL-2.0-only OR MIT */
/* STRING/WSTRING layout, views, truncation and conversions. */
#include "iec_string.h"
#include "check.h"

IEC_DECLARE_STRING(5);
IEC_DECLARE_WSTRING(3);

int main(void)
{
	struct iec_string s = { 0 }, t = { 0 };
	struct iec_string_5 s5;
	struct iec_wstring w = { 0 };
	struct iec_wstring_3 w3;
	struct iec_strv v;

	CHECK_U(sizeof(s5.data), 6);
	CHECK_U(sizeof(s.data), IEC_STRING_DEFAULT_LEN + 1);
	CHECK_U(IEC_STR_CAP(s5), 5);
	CHECK_U(IEC_STR_CAP(w3), 3);
	memset(&s5, 'x', sizeof(s5));

	/* assignment truncates to the capacity, terminator kept */
	iec_assign_string(IEC_SB(s5), IEC_SLIT("abcdefgh"));
	CHECK_STR(s5, "abcde");
	iec_concat_string(IEC_SB(s5), IEC_SV(s5), IEC_SLIT("z"));
	CHECK_STR(s5, "abcde");
	iec_right_string(IEC_SB(s5), IEC_SV(s5), 2);
	CHECK_STR(s5, "de");

	/* a corrupted length is clamped by the view */
	s5.len = 999;
	v = IEC_SV(s5);
	CHECK_U(v.len, 5);

	/* literals with an embedded NUL */
	v = IEC_SLIT("a\0b");
	CHECK_U(v.len, 3);
	CHECK_I(iec_len_string(v), 3);
	iec_assign_string(IEC_SB(s), v);
	CHECK_U(s.len, 3);
	CHECK(s.data[1] == 0 && s.data[2] == 'b' && s.data[3] == 0);

	/* comparisons */
	CHECK(iec_lt_string(IEC_SLIT("ab"), IEC_SLIT("abc")));
	CHECK(iec_gt_string(IEC_SLIT("b"), IEC_SLIT("abc")));
	CHECK(iec_eq_string(IEC_SLIT(""), IEC_SLIT("")));
	CHECK(iec_gt_string(IEC_SLIT("\xff"), IEC_SLIT("a")));
	CHECK(iec_ne_string(IEC_SLIT("a"), IEC_SLIT("A")));
	CHECK(iec_le_string(IEC_SLIT("a"), IEC_SLIT("a")));
	CHECK(iec_ge_string(IEC_SLIT("a"), IEC_SLIT("a")));

	/* CHAR */
	iec_char_to_string(IEC_SB(t), 'Q');
	CHECK_STR(t, "Q");
	CHECK_I(iec_string_to_char(IEC_SLIT("xyz")), 'x');
	CHECK_I(iec_string_to_char(IEC_SLIT("")), 0);

	/* WSTRING <-> STRING */
	iec_string_to_wstring(IEC_WSB(w), IEC_SLIT("A\xe9"));
	CHECK_U(w.len, 2);
	CHECK_U(w.data[1], 0xe9);
	CHECK_U(w.data[2], 0);
	iec_concat_wstring(IEC_WSB(w), IEC_WSV(w), IEC_WSLIT(u"\u263a"));
	CHECK_U(w.len, 3);
	iec_wstring_to_string(IEC_SB(t), IEC_WSV(w));
	CHECK_STR(t, "A\xe9?");
	iec_assign_wstring(IEC_WSB(w3), IEC_WSLIT(u"abcd"));
	CHECK_U(w3.len, 3);
	CHECK_U(w3.data[3], 0);
	CHECK(iec_lt_wstring(IEC_WSLIT(u"a"), IEC_WSLIT(u"\u263a")));
	CHECK_I(iec_find_wstring(IEC_WSLIT(u"xx\u263ay"), IEC_WSLIT(u"\u263a")), 3);
	iec_wchar_to_wstring(IEC_WSB(w3), 0x263a);
	CHECK_U(w3.len, 1);
	CHECK_U(iec_wstring_to_wchar(IEC_WSV(w3)), 0x263a);

	/* numbers to WSTRING and back */
	iec_dint_to_wstring(IEC_WSB(w), -42);
	CHECK_U(w.len, 3);
	CHECK_I(iec_wstring_to_dint(IEC_WSV(w)), -42);
	CHECK_I(iec_wstring_to_int(IEC_WSLIT(u"  16#7FFF  ")), 32767);
	CHECK_I(iec_wstring_to_int(IEC_WSLIT(u"1\u263a")), 0);
	iec_time_to_wstring(IEC_WSB(w3), 1500000000);
	CHECK_U(w3.len, 3);	/* "T#1" truncated */
	CHECK_I(iec_wstring_to_time(IEC_WSLIT(u"T#1s500ms")), 1500000000);

	/* the formats */
	iec_time_to_string(IEC_SB(t), 0);
	CHECK_STR(t, "T#0s");
	iec_time_to_string(IEC_SB(t), -1500000000LL);
	CHECK_STR(t, "T#-1s500ms");
	iec_date_to_string(IEC_SB(t), 0);
	CHECK_STR(t, "D#1970-01-01");
	iec_tod_to_string(IEC_SB(t), 45296789000000LL);
	CHECK_STR(t, "TOD#12:34:56.789");
	iec_dt_to_string(IEC_SB(t), -1);
	CHECK_STR(t, "DT#1969-12-31-23:59:59.999999999");
	iec_ldt_to_string(IEC_SB(t), 0);
	CHECK_STR(t, "LDT#1970-01-01-00:00:00");
	iec_ulint_to_string(IEC_SB(t), 18446744073709551615ull);
	CHECK_STR(t, "18446744073709551615");
	iec_lint_to_string(IEC_SB(t), IEC_S64_MIN);
	CHECK_STR(t, "-9223372036854775808");
	iec_byte_to_string(IEC_SB(t), 255);
	CHECK_STR(t, "255");
	iec_lint_to_string(IEC_SB(s5), IEC_S64_MIN);
	CHECK_STR(s5, "-9223");
	CHECK_DONE();
}
