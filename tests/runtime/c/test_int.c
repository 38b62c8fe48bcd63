/* SPDX-License-Identifier: GPL-2.0-only OR MIT */
/* Integer arithmetic, bit strings, selection, faults, conversions, time. */
#include "iec_int.h"
#include "iec_conv.h"
#include "iec_time.h"
#include "check.h"

static void test_wrap(void)
{
	CHECK_I(iec_add_int(32767, 1), -32768);
	CHECK_I(iec_sub_int(-32768, 1), 32767);
	CHECK_I(iec_mul_int(300, 300), (short)(90000 - 65536));
	CHECK_I(iec_mul_uint(65535, 65535), 1);
	CHECK_I(iec_mul_usint(255, 255), 1);
	CHECK_I(iec_add_sint(127, 1), -128);
	CHECK_I(iec_neg_sint(-128), -128);
	CHECK_I(iec_abs_sint(-128), -128);
	CHECK_I(iec_abs_int(-5), 5);
	CHECK_I(iec_add_dint(IEC_S32_MAX, 1), IEC_S32_MIN);
	CHECK_I(iec_mul_dint(65536, 65536), 0);
	CHECK_I(iec_add_lint(IEC_S64_MAX, 1), IEC_S64_MIN);
	CHECK_I(iec_mul_lint(IEC_S64_MIN, -1), IEC_S64_MIN);
	CHECK_I(iec_neg_lint(IEC_S64_MIN), IEC_S64_MIN);
	CHECK_I(iec_abs_lint(IEC_S64_MIN), IEC_S64_MIN);
	CHECK_U(iec_sub_ulint(0, 1), IEC_U64_MAX);
	CHECK_U(iec_sub_usint(0, 1), 255);
	CHECK_U(iec_abs_udint(7), 7);
}

static void test_div(void)
{
	struct iec_ctx ctx;

	iec_ctx_init(&ctx, 0);
	CHECK_I(iec_div_int(&ctx, 7, 2), 3);
	CHECK_I(iec_div_int(&ctx, -7, 2), -3);
	CHECK_I(iec_mod_int(&ctx, -7, 2), -1);
	CHECK_I(iec_mod_int(&ctx, 7, -2), 1);
	CHECK_I(iec_div_sint(&ctx, -128, -1), -128);
	CHECK_I(iec_mod_sint(&ctx, -128, -1), 0);
	CHECK_I(iec_div_int(&ctx, -32768, -1), -32768);
	CHECK_I(iec_div_dint(&ctx, IEC_S32_MIN, -1), IEC_S32_MIN);
	CHECK_I(iec_mod_dint(&ctx, IEC_S32_MIN, -1), 0);
	CHECK_I(iec_div_lint(&ctx, IEC_S64_MIN, -1), IEC_S64_MIN);
	CHECK_I(iec_mod_lint(&ctx, IEC_S64_MIN, -1), 0);
	CHECK_U(iec_div_ulint(&ctx, IEC_U64_MAX, 2), IEC_U64_MAX / 2);
	CHECK_I(ctx.fault, IEC_FAULT_NONE);
	CHECK_I(ctx.fault_count, 0);

	CHECK_I(iec_div_dint(&ctx, 5, 0), 0);
	CHECK_I(ctx.fault, IEC_FAULT_DIV_ZERO);
	CHECK_I(ctx.fault_count, 1);
	CHECK_I(iec_mod_udint(&ctx, 5, 0), 0);
	CHECK_I(ctx.fault_count, 2);
	/* the first fault is kept */
	CHECK_U(iec_index(&ctx, 11, 0, 10), 0);
	CHECK_I(ctx.fault, IEC_FAULT_DIV_ZERO);
	CHECK_I(ctx.fault_count, 3);
	iec_fault_clear(&ctx);
	CHECK_I(ctx.fault, IEC_FAULT_NONE);
	CHECK_I(ctx.fault_count, 0);

	CHECK_I(iec_div_usint(&ctx, 1, 0), 0);
	CHECK_I(ctx.fault, IEC_FAULT_DIV_ZERO);
	iec_fault_clear(&ctx);
	CHECK_I(iec_mod_lint(&ctx, 1, 0), 0);
	CHECK_I(ctx.fault, IEC_FAULT_DIV_ZERO);
}

static void test_checks(void)
{
	struct iec_ctx ctx;

	iec_ctx_init(&ctx, 0);
	CHECK_U(iec_index(&ctx, 5, 1, 10), 4);
	CHECK_U(iec_index(&ctx, -3, -3, 3), 0);
	CHECK_U(iec_index(&ctx, 3, -3, 3), 6);
	CHECK_U(iec_index(&ctx, IEC_S64_MAX, IEC_S64_MIN, IEC_S64_MAX),
		IEC_U64_MAX);
	CHECK_I(ctx.fault, IEC_FAULT_NONE);
	CHECK_U(iec_index(&ctx, 0, 1, 10), 0);
	CHECK_I(ctx.fault, IEC_FAULT_INDEX);

	iec_fault_clear(&ctx);
	CHECK_I(iec_range_lint(&ctx, 5, 0, 10), 5);
	CHECK_I(ctx.fault, IEC_FAULT_NONE);
	CHECK_I(iec_range_lint(&ctx, 11, 2, 10), 2);
	CHECK_I(ctx.fault, IEC_FAULT_RANGE);

	iec_fault_clear(&ctx);
	CHECK_U(iec_range_ulint(&ctx, 300, 0, 255), 0);
	CHECK_I(ctx.fault, IEC_FAULT_RANGE);

	iec_fault_clear(&ctx);
	CHECK_I(iec_enum_check(&ctx, 2, 0, 3, 0), 2);
	CHECK_I(iec_enum_check(&ctx, 7, 0, 3, 1), 1);
	CHECK_I(ctx.fault, IEC_FAULT_ENUM);

	iec_fault_clear(&ctx);
	CHECK_U(iec_mux_index(&ctx, 2, 3), 2);
	CHECK_U(iec_mux_index(&ctx, 3, 3), 0);
	CHECK_I(ctx.fault, IEC_FAULT_MUX);
	iec_fault_clear(&ctx);
	CHECK_U(iec_mux_index(&ctx, -1, 3), 0);
	CHECK_I(ctx.fault, IEC_FAULT_MUX);
	CHECK(iec_fault_name(IEC_FAULT_LOOP)[0] == 'e');
}

/* A POU-like function following the documented protocol. */
static int pou_runs, pou_after_loop;

static void pou_endless(struct iec_ctx *ctx)
{
	pou_runs++;
	for (;;)
		IEC_LOOP_TICK(ctx, "ENDLESS", 12);
	pou_after_loop++;
}

static void pou_caller(struct iec_ctx *ctx)
{
	int x = iec_div_int(ctx, 1, 1);

	IEC_FAULT_CHECK(ctx, "CALLER", 3);
	pou_endless(ctx);
	IEC_FAULT_CHECK(ctx, "CALLER", 4);
	pou_after_loop += x;
}

static void test_loop_budget(void)
{
	struct iec_ctx ctx;
	iec_u32 i;

	iec_ctx_init(&ctx, 1000);
	iec_ctx_cycle_begin(&ctx, 5);
	CHECK_I(ctx.now_ns, 5);
	for (i = 0; i < 1000; i++)
		if (!iec_loop_tick(&ctx))
			break;
	CHECK_U(i, 1000);
	CHECK_I(ctx.fault, IEC_FAULT_NONE);
	CHECK(!iec_loop_tick(&ctx));
	CHECK_I(ctx.fault, IEC_FAULT_LOOP);

	iec_fault_clear(&ctx);
	iec_ctx_cycle_begin(&ctx, 10);
	CHECK_U(ctx.loop_budget, 1000);
	pou_caller(&ctx);
	CHECK_I(pou_runs, 1);
	CHECK_I(pou_after_loop, 0);
	CHECK_I(ctx.fault, IEC_FAULT_LOOP);
	CHECK(ctx.fault_pou && strcmp(ctx.fault_pou, "ENDLESS") == 0);
	CHECK_I(ctx.fault_line, 12);

	/* a pending fault makes the next body return at its first check */
	iec_ctx_cycle_begin(&ctx, 20);
	pou_caller(&ctx);
	CHECK_I(pou_runs, 1);

	iec_ctx_init(&ctx, 0);
	CHECK_U(ctx.loop_budget, IEC_LOOP_BUDGET_DEFAULT);
}

static void test_bits(void)
{
	CHECK_U(iec_shl_byte(0x81, 1), 0x02);
	CHECK_U(iec_shl_byte(0x81, 8), 0);
	CHECK_U(iec_shl_byte(0x81, -1), 0);
	CHECK_U(iec_shr_word(0x8000, 15), 1);
	CHECK_U(iec_shr_word(0x8000, 16), 0);
	CHECK_U(iec_shl_dword(1, 31), 0x80000000u);
	CHECK_U(iec_shl_lword(1, 63), 0x8000000000000000ull);
	CHECK_U(iec_shl_lword(1, 64), 0);
	CHECK_U(iec_shl_lword(1, IEC_S64_MIN), 0);
	CHECK_U(iec_rol_byte(0x81, 1), 0x03);
	CHECK_U(iec_ror_byte(0x81, 1), 0xc0);
	CHECK_U(iec_rol_byte(0x81, 9), 0x03);
	CHECK_U(iec_rol_byte(0x81, -1), 0xc0);
	CHECK_U(iec_rol_byte(0x81, 8), 0x81);
	CHECK_U(iec_rol_word(0x8001, 4), 0x0018);
	CHECK_U(iec_ror_dword(1, 1), 0x80000000u);
	CHECK_U(iec_rol_lword(0x8000000000000001ull, 1), 3);
	CHECK_U(iec_ror_lword(3, 65), 0x8000000000000001ull);
	CHECK_U(iec_rol_lword(5, IEC_S64_MIN), 5);
	CHECK_U(iec_not_byte(0x0f), 0xf0);
	CHECK_U(iec_not_word(0), 0xffff);
	CHECK_U(iec_not_lword(0), IEC_U64_MAX);
	CHECK_U(iec_and_word(0xff0f, 0x0ff0), 0x0f00);
	CHECK_U(iec_or_dword(0xf0, 0x0f), 0xff);
	CHECK_U(iec_xor_byte(0xff, 0x0f), 0xf0);
	CHECK_I(iec_not_bool(0), 1);
	CHECK_I(iec_not_bool(2), 0);
	CHECK_I(iec_and_bool(2, 4), 1);
	CHECK_I(iec_or_bool(0, 0), 0);
	CHECK_I(iec_xor_bool(2, 1), 0);
	CHECK_I(iec_xor_bool(0, 1), 1);
}

static void test_select(void)
{
	CHECK_I(iec_sel_int(0, 1, 2), 1);
	CHECK_I(iec_sel_int(1, 1, 2), 2);
	CHECK_I(iec_max_dint(-3, 2), 2);
	CHECK_I(iec_min_dint(-3, 2), -3);
	CHECK_I(iec_limit_int(0, -5, 10), 0);
	CHECK_I(iec_limit_int(0, 50, 10), 10);
	CHECK_I(iec_limit_int(0, 5, 10), 5);
	CHECK_U(iec_max_ulint(IEC_U64_MAX, 0), IEC_U64_MAX);
	CHECK_I(iec_max_time(5, 7), 7);
	CHECK_I(iec_move_word(0xabcd), 0xabcd);
	CHECK_I(iec_gt_int(2, 1), 1);
	CHECK_I(iec_ge_int(1, 1), 1);
	CHECK_I(iec_eq_int(1, 2), 0);
	CHECK_I(iec_le_udint(1, 2), 1);
	CHECK_I(iec_lt_udint(2, 2), 0);
	CHECK_I(iec_ne_udint(2, 3), 1);
}

static void test_conv(void)
{
	CHECK_I(iec_int_to_sint(300), 44);
	CHECK_I(iec_int_to_sint(-129), 127);
	CHECK_U(iec_dint_to_uint(-1), 65535);
	CHECK_U(iec_sint_to_ulint(-1), IEC_U64_MAX);
	CHECK_I(iec_ulint_to_lint(IEC_U64_MAX), -1);
	CHECK_I(iec_lword_to_dint(0x1ffffffffull), -1);
	CHECK_I(iec_byte_to_sint(0x80), -128);
	CHECK_U(iec_char_to_word(0x41), 0x41);
	CHECK_U(iec_wchar_to_char(0x1234), 0x34);
	CHECK_I(iec_int_to_int(-5), -5);
	CHECK_I(iec_int_to_bool(0), 0);
	CHECK_I(iec_int_to_bool(-7), 1);
	CHECK_I(iec_lword_to_bool(1ull << 63), 1);
	CHECK_I(iec_bool_to_dint(1), 1);
	CHECK_I(iec_bool_to_dint(0), 0);
	CHECK_I(iec_bool_to_bool(5), 1);

	/* TIME <-> integers: milliseconds, LTIME: nanoseconds */
	CHECK_I(iec_time_to_dint(1500 * IEC_NS_PER_MS + 999999), 1500);
	CHECK_I(iec_time_to_dint(-(1500 * IEC_NS_PER_MS + 999999)), -1500);
	CHECK_I(iec_dint_to_time(-250), -250 * IEC_NS_PER_MS);
	CHECK_I(iec_ltime_to_lint(12345), 12345);
	CHECK_I(iec_lint_to_ltime(-7), -7);
	CHECK_I(iec_udint_to_time(IEC_U32_MAX), (long long)IEC_U32_MAX * IEC_NS_PER_MS);
	CHECK_I(iec_time_to_int(70000 * IEC_NS_PER_MS), (short)70000);
	/* wrap, never UB */
	CHECK_I(iec_lint_to_time(IEC_S64_MAX),
		(long long)((unsigned long long)IEC_S64_MAX * 1000000ull));
	/* points in time floor */
	CHECK_I(iec_dt_to_udint(1700000000LL * IEC_NS_PER_S + 999), 1700000000);
	CHECK_I(iec_dt_to_lint(-1), -1);
	CHECK_I(iec_date_to_udint(3 * IEC_NS_PER_DAY), 3 * 86400);
	CHECK_I(iec_udint_to_date(3 * 86400 + 5), 3 * IEC_NS_PER_DAY);
	CHECK_I(iec_lint_to_date(-1), -IEC_NS_PER_DAY);
	CHECK_I(iec_udint_to_tod(86400000 + 5), 5 * IEC_NS_PER_MS);
	CHECK_I(iec_tod_to_udint(12 * IEC_NS_PER_H), 12 * 3600000);
	CHECK_I(iec_lint_to_ltod(-1), IEC_NS_PER_DAY - 1);
	CHECK_I(iec_lint_to_date(IEC_S64_MIN) % IEC_NS_PER_DAY, 0);
	CHECK_I(iec_dt_to_date(-1), -IEC_NS_PER_DAY);
	CHECK_I(iec_dt_to_tod(-1), IEC_NS_PER_DAY - 1);
	/* below the representable range: wraps, defined */
	CHECK_U((unsigned long long)iec_dt_to_date(IEC_S64_MIN),
		(unsigned long long)IEC_S64_MIN -
		(unsigned long long)iec__floormod(IEC_S64_MIN, IEC_NS_PER_DAY));
	CHECK_I(iec_ldt_to_ltod(IEC_NS_PER_DAY + 7), 7);
	CHECK_I(iec_time_to_ltime(9), 9);

	/* BCD */
	CHECK_U(iec_byte_bcd_to_usint(0x42), 42);
	CHECK_U(iec_byte_bcd_to_usint(0x4a), 0);
	CHECK_U(iec_word_bcd_to_uint(0x9999), 9999);
	CHECK_U(iec_dword_bcd_to_udint(0x12345678), 12345678);
	CHECK_U(iec_lword_bcd_to_ulint(0x9999999999999999ull),
		9999999999999999ull);
	CHECK_U(iec_usint_to_bcd_byte(99), 0x99);
	CHECK_U(iec_usint_to_bcd_byte(100), 0);
	CHECK_U(iec_uint_to_bcd_word(1234), 0x1234);
	CHECK_U(iec_udint_to_bcd_dword(87654321), 0x87654321);
	CHECK_U(iec_ulint_to_bcd_lword(IEC_U64_MAX), 0);
	CHECK_U(iec_ulint_to_bcd_lword(1234567890123456ull),
		0x1234567890123456ull);
}

static void test_time(void)
{
	struct iec_ctx ctx;
	iec_lint y, mo, d, h, mi, s, ms;

	iec_ctx_init(&ctx, 0);
	CHECK_I(iec_add_time(IEC_NS_PER_S, 500 * IEC_NS_PER_MS),
		1500 * IEC_NS_PER_MS);
	CHECK_I(iec_add_time(IEC_S64_MAX, 1), IEC_S64_MIN);
	CHECK_I(iec_sub_time(IEC_S64_MIN, 1), IEC_S64_MAX);
	CHECK_I(iec_mul_time(IEC_NS_PER_S, 3), 3 * IEC_NS_PER_S);
	CHECK_I(iec_div_time(&ctx, 3 * IEC_NS_PER_S, 2), 1500 * IEC_NS_PER_MS);
	CHECK_I(iec_div_time(&ctx, IEC_S64_MIN, -1), IEC_S64_MIN);
	CHECK_I(ctx.fault, IEC_FAULT_NONE);
	CHECK_I(iec_div_time(&ctx, IEC_NS_PER_S, 0), 0);
	CHECK_I(ctx.fault, IEC_FAULT_DIV_ZERO);
	CHECK_I(iec_add_tod_time(23 * IEC_NS_PER_H, 2 * IEC_NS_PER_H),
		1 * IEC_NS_PER_H);
	CHECK_I(iec_sub_tod_time(1 * IEC_NS_PER_H, 2 * IEC_NS_PER_H),
		23 * IEC_NS_PER_H);
	CHECK_I(iec_add_tod_time(0, IEC_S64_MIN),
		iec__floormod(IEC_S64_MIN, IEC_NS_PER_DAY));
	CHECK_I(iec_sub_tod_tod(IEC_NS_PER_H, 2 * IEC_NS_PER_H), -IEC_NS_PER_H);
	CHECK_I(iec_sub_date_date(IEC_NS_PER_DAY, 0), IEC_NS_PER_DAY);
	CHECK_I(iec_add_dt_time(IEC_NS_PER_DAY, -1), IEC_NS_PER_DAY - 1);
	CHECK_I(iec_sub_dt_dt(5, 7), -2);
	CHECK_I(iec_concat_date_tod(IEC_NS_PER_DAY, 5), IEC_NS_PER_DAY + 5);

	CHECK_I(iec_concat_date(1970, 1, 1), 0);
	CHECK_I(iec_concat_date(2000, 3, 1) / IEC_NS_PER_DAY, 11017);
	CHECK_I(iec_concat_date(1969, 12, 31), -IEC_NS_PER_DAY);
	CHECK_I(iec_concat_date(2023, 13, 1), iec_concat_date(2024, 1, 1));
	CHECK_I(iec_concat_date(2024, 0, 1), iec_concat_date(2023, 12, 1));
	CHECK_I(iec_concat_tod(12, 34, 56, 789),
		((12 * 60 + 34) * 60 + 56) * IEC_NS_PER_S + 789 * IEC_NS_PER_MS);
	CHECK_I(iec_concat_tod(24, 0, 0, 0), 0);
	iec_split_dt(iec_concat_dt(2024, 2, 29, 23, 59, 58, 7), &y, &mo, &d, &h,
		     &mi, &s, &ms);
	CHECK_I(y, 2024);
	CHECK_I(mo, 2);
	CHECK_I(d, 29);
	CHECK_I(h, 23);
	CHECK_I(mi, 59);
	CHECK_I(s, 58);
	CHECK_I(ms, 7);
	iec_split_date(iec_concat_date(1900, 2, 28), &y, &mo, &d);
	CHECK_I(y * 10000 + mo * 100 + d, 19000228);
	iec_split_date(iec_concat_date(1900, 2, 29), &y, &mo, &d);
	CHECK_I(y * 10000 + mo * 100 + d, 19000301);
	CHECK_I(iec_day_of_week(0), 4);
	CHECK_I(iec_day_of_week(-IEC_NS_PER_DAY), 3);
	CHECK_I(iec_day_of_week(iec_concat_date(2024, 6, 2)), 0);
	/* extreme fields do not overflow (results wrap, defined) */
	(void)iec_concat_dt(IEC_S64_MAX, IEC_S64_MIN, IEC_S64_MAX, IEC_S64_MAX,
			    IEC_S64_MIN, IEC_S64_MAX, IEC_S64_MIN);
	iec_split_dt(IEC_S64_MIN, &y, &mo, &d, &h, &mi, &s, &ms);
	CHECK_I(y, 1677);
	iec_split_dt(IEC_S64_MAX, &y, &mo, &d, &h, &mi, &s, &ms);
	CHECK_I(y * 10000 + mo * 100 + d, 22620411);
}

int main(void)
{
	test_wrap();
	test_div();
	test_checks();
	test_loop_budget();
	test_bits();
	test_select();
	test_conv();
	test_time();
	CHECK_DONE();
}
