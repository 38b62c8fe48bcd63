/* SPDX-License-Identifier: GPL-2.0-only OR MIT */
/* REAL/LREAL: conversions (rounding, saturation), special values, exact
 * cases of the math functions, time and string conversions. */
#include "iec_real.h"
#include "check.h"

#define NANF __builtin_nanf("")
#define INF __builtin_inf()

static int isnan_(double x)
{
	return x != x;
}

static int same(double a, double b)
{
	return (isnan_(a) && isnan_(b)) || a == b;
}

int main(void)
{
	struct iec_ctx ctx;
	struct iec_string s;
	double pi = 3.141592653589793;

	iec_ctx_init(&ctx, 0);

	/* ties to even */
	CHECK_I(iec_real_to_int(2.5f), 2);
	CHECK_I(iec_real_to_int(3.5f), 4);
	CHECK_I(iec_real_to_int(-2.5f), -2);
	CHECK_I(iec_real_to_int(-3.5f), -4);
	CHECK_I(iec_real_to_int(0.5f), 0);
	CHECK_I(iec_real_to_int(1.5f), 2);
	CHECK_I(iec_real_to_int(1.4999999f), 1);
	CHECK_I(iec_lreal_to_dint(-0.49999999999999994), 0);
	CHECK_I(iec_lreal_to_lint(4503599627370497.0), 4503599627370497LL);
	CHECK_I(iec_lreal_to_lint(-4503599627370497.0), -4503599627370497LL);
	/* saturation, NaN */
	CHECK_I(iec_real_to_int(40000.0f), IEC_S16_MAX);
	CHECK_I(iec_real_to_int(-40000.0f), IEC_S16_MIN);
	CHECK_I(iec_real_to_int(32767.5f), IEC_S16_MAX);
	CHECK_I(iec_real_to_int(-32768.5f), IEC_S16_MIN);
	CHECK_I(iec_real_to_int(32766.5f), 32766);
	CHECK_I(iec_real_to_sint(NANF), 0);
	CHECK_I(iec_lreal_to_lint(INF), IEC_S64_MAX);
	CHECK_I(iec_lreal_to_lint(-INF), IEC_S64_MIN);
	CHECK_I(iec_lreal_to_lint(9223372036854775807.0), IEC_S64_MAX);
	CHECK_I(iec_lreal_to_lint(-9223372036854775808.0), IEC_S64_MIN);
	CHECK_U(iec_lreal_to_ulint(18446744073709551616.0), IEC_U64_MAX);
	CHECK_U(iec_lreal_to_ulint(18446744073709549568.0),
		18446744073709549568ull);
	CHECK_U(iec_lreal_to_ulint(-1.0), 0);
	CHECK_U(iec_lreal_to_ulint(-0.5), 0);
	CHECK_U(iec_real_to_usint(255.5f), 255);
	CHECK_U(iec_real_to_usint(254.5f), 254);
	CHECK_U(iec_real_to_byte(300.0f), 255);
	CHECK_U(iec_lreal_to_dword(-3.0), 0);
	/* TRUNC */
	CHECK_I(iec_real_trunc_int(2.9f), 2);
	CHECK_I(iec_real_trunc_int(-2.9f), -2);
	CHECK_I(iec_lreal_trunc_dint(1e10), IEC_S32_MAX);
	CHECK_I(iec_lreal_trunc_dint(-2147483648.9), IEC_S32_MIN);
	CHECK_I(iec_lreal_trunc_dint(-2147483649.0), IEC_S32_MIN);
	CHECK_I(iec_lreal_trunc_lint(NANF), 0);
	CHECK_U(iec_lreal_trunc_udint(4294967295.9), IEC_U32_MAX);
	CHECK_U(iec_lreal_trunc_ulint(-0.9), 0);
	/* to REAL */
	CHECK(iec_ulint_to_real(IEC_U64_MAX) == 18446744073709551616.0f);
	CHECK(iec_lint_to_lreal(IEC_S64_MIN) == -9223372036854775808.0);
	CHECK(iec_dint_to_real(16777217) == 16777216.0f);
	CHECK(iec_int_to_lreal(-5) == -5.0);
	/* REAL <-> LREAL, BOOL */
	CHECK(iec_lreal_to_real(1e300) == __builtin_inff());
	CHECK(iec_lreal_to_real(-1e300) == -__builtin_inff());
	CHECK(iec_lreal_to_real(3.4028235677973362e38) == 3.4028234663852886e38f);
	CHECK(iec_lreal_to_real(3.4028235677973366e38) == __builtin_inff());
	CHECK(iec_lreal_to_real(0.1) == 0.1f);
	CHECK(isnan_(iec_lreal_to_real(NANF)));
	CHECK_I(iec_real_to_bool(0.0f), 0);
	CHECK_I(iec_real_to_bool(-0.0f), 0);
	CHECK_I(iec_lreal_to_bool(1e-300), 1);
	CHECK(iec_bool_to_lreal(1) == 1.0);

	/* arithmetic and selection */
	CHECK(iec_div_lreal(1.0, 0.0) == INF);
	CHECK(isnan_(iec_max_real(NANF, 1.0f)));
	CHECK(isnan_(iec_min_lreal(1.0, NANF)));
	CHECK(iec_max_lreal(-1.0, 2.0) == 2.0);
	CHECK(iec_limit_real(0.0f, 5.0f, 1.0f) == 1.0f);
	CHECK(iec_abs_lreal(-2.0) == 2.0);
	CHECK(iec_sel_lreal(1, 1.0, 2.0) == 2.0);

	/* domains and special values */
	CHECK(isnan_(iec_sqrt_lreal(-1.0)));
	CHECK(isnan_(iec_sqrt_real(-1.0f)));
	CHECK(iec_sqrt_lreal(-0.0) == 0.0);
	CHECK(iec_ln_lreal(0.0) == -INF);
	CHECK(isnan_(iec_ln_lreal(-1.0)));
	CHECK(iec_log_real(0.0f) == -__builtin_inff());
	CHECK(isnan_(iec_log_lreal(-1e-300)));
	CHECK(isnan_(iec_asin_lreal(1.0000000000000002)));
	CHECK(isnan_(iec_acos_real(-1.5f)));
	CHECK(iec_exp_lreal(1000.0) == INF);
	CHECK(iec_exp_lreal(-1000.0) == 0.0);
	CHECK(isnan_(iec_sin_lreal(INF)));
	CHECK(isnan_(iec_cos_lreal(-INF)));
	CHECK(isnan_(iec_tan_lreal(NANF)));
	CHECK(iec_atan_lreal(INF) == pi / 2);
	CHECK(iec_atan2_lreal(0.0, -0.0) == pi);
	CHECK(iec_atan2_lreal(-0.0, -1.0) == -pi);
	CHECK(iec_atan2_lreal(1.0, 0.0) == pi / 2);
	CHECK(iec_atan2_lreal(INF, -INF) == 3 * pi / 4);
	CHECK(isnan_(iec_expt_lreal(-8.0, 1.0 / 3)));
	CHECK(iec_expt_lreal(-8.0, 3.0) == -512.0);
	CHECK(iec_expt_lreal(-2.0, 2.0) == 4.0);
	CHECK(iec_expt_lreal(0.0, -1.0) == INF);
	CHECK(iec_expt_lreal(-0.0, -1.0) == -INF);
	CHECK(iec_expt_lreal(NANF, 0.0) == 1.0);
	CHECK(iec_expt_lreal(1.0, NANF) == 1.0);
	CHECK(iec_expt_lreal(-1.0, INF) == 1.0);
	CHECK(iec_expt_lreal(0.5, INF) == 0.0);
	CHECK(iec_expt_lreal(2.0, 1e300) == INF);
	CHECK(iec_expt_lreal(2.0, -1e300) == 0.0);
	CHECK(iec_expt_lreal(10.0, 400.0) == INF);

	/* exact cases stay exact */
	CHECK(iec_expt_lreal(3.0, 2.0) == 9.0);
	CHECK(iec_expt_lreal(2.0, 10.0) == 1024.0);
	CHECK(iec_expt_lreal(10.0, 15.0) == 1e15);
	CHECK(iec_expt_lreal(2.0, -1074.0) == 0x1p-1074);
	CHECK(iec_expt_lreal(4.0, 0.5) == 2.0);
	CHECK(iec_expt_real(10.0f, 3.0f) == 1000.0f);
	CHECK(iec_expt_real_lint(-2.0f, 3) == -8.0f);
	CHECK(iec_expt_lreal_lint(1.5, 2) == 2.25);
	CHECK(iec_log_lreal(1000.0) == 3.0);
	CHECK(iec_log_lreal(1e-300) == -300.0);
	CHECK(iec_log_real(100.0f) == 2.0f);
	CHECK(iec_ln_lreal(1.0) == 0.0);
	CHECK(iec_exp_lreal(0.0) == 1.0);
	CHECK(iec_sin_lreal(0.0) == 0.0);
	CHECK(iec_cos_lreal(0.0) == 1.0);
	CHECK(iec_sqrt_lreal(2.25) == 1.5);
	CHECK(iec_exp_lreal(1.0) == 2.718281828459045);
	CHECK(iec_atan_lreal(1.0) == pi / 4);
	CHECK(iec_asin_lreal(1.0) == pi / 2);
	CHECK(iec_acos_lreal(-1.0) == pi);
	CHECK(iec_sin_real(3.14159265f) == -8.742278e-08f);

	/* time */
	CHECK_I(iec_lreal_to_time(1.5), 1500000);
	CHECK_I(iec_real_to_time(0.0000015f), 2);	/* 1.5 ns -> even */
	CHECK_I(iec_lreal_to_time(1e300), IEC_S64_MAX);
	CHECK_I(iec_lreal_to_time(NANF), 0);
	CHECK(iec_time_to_lreal(1500000) == 1.5);
	CHECK(iec_ltime_to_lreal(7) == 7.0);
	CHECK(iec_dt_to_lreal(IEC_NS_PER_DAY) == 86400.0);
	CHECK_I(iec_lreal_to_date(1.5 * 86400), IEC_NS_PER_DAY);
	CHECK_I(iec_lreal_to_tod(-1.0), IEC_NS_PER_DAY - IEC_NS_PER_MS);
	CHECK_I(iec_mul_time_lreal(IEC_NS_PER_S, 2.5), 2500000000LL);
	CHECK_I(iec_mul_time_real(IEC_NS_PER_S, 0.5f), 500000000LL);
	CHECK_I(iec_div_time_lreal(&ctx, IEC_NS_PER_S, 4.0), 250000000LL);
	CHECK_I(ctx.fault, IEC_FAULT_NONE);
	CHECK_I(iec_div_time_lreal(&ctx, IEC_NS_PER_S, 0.0), 0);
	CHECK_I(ctx.fault, IEC_FAULT_DIV_ZERO);

	/* strings */
	iec_lreal_to_string(IEC_SB(s), 0.1);
	CHECK_STR(s, "0.1");
	iec_lreal_to_string(IEC_SB(s), -3.0);
	CHECK_STR(s, "-3.0");
	iec_lreal_to_string(IEC_SB(s), 1e20);
	CHECK_STR(s, "1.0E+20");
	iec_lreal_to_string(IEC_SB(s), 2.5e-7);
	CHECK_STR(s, "2.5E-7");
	iec_lreal_to_string(IEC_SB(s), 123456.789);
	CHECK_STR(s, "123456.789");
	iec_lreal_to_string(IEC_SB(s), -0.0);
	CHECK_STR(s, "-0.0");
	iec_lreal_to_string(IEC_SB(s), INF);
	CHECK_STR(s, "Inf");
	iec_lreal_to_string(IEC_SB(s), -INF);
	CHECK_STR(s, "-Inf");
	iec_lreal_to_string(IEC_SB(s), NANF);
	CHECK_STR(s, "NaN");
	iec_real_to_string(IEC_SB(s), 0.1f);
	CHECK_STR(s, "0.1");
	iec_real_to_string(IEC_SB(s), 16777216.0f);
	CHECK_STR(s, "1.6777216E+7");
	iec_real_to_string(IEC_SB(s), 3.4028234663852886e38f);
	CHECK_STR(s, "3.4028235E+38");
	iec_lreal_to_string(IEC_SB(s), 5e-324);
	CHECK_STR(s, "5.0E-324");
	iec_lreal_to_string(IEC_SB(s), 1.7976931348623157e308);
	CHECK_STR(s, "1.7976931348623157E+308");
	CHECK(iec_string_to_lreal(IEC_SLIT("1.5")) == 1.5);
	CHECK(iec_string_to_lreal(IEC_SLIT(" -2E3 ")) == -2000.0);
	CHECK(iec_string_to_lreal(IEC_SLIT("1_000.5")) == 1000.5);
	CHECK(iec_string_to_lreal(IEC_SLIT("LREAL#0.1")) == 0.1);
	CHECK(iec_string_to_real(IEC_SLIT("REAL#3.5")) == 3.5f);
	CHECK(iec_string_to_real(IEC_SLIT("0.1")) == 0.1f);
	CHECK(iec_string_to_lreal(IEC_SLIT("1e400")) == INF);
	CHECK(iec_string_to_lreal(IEC_SLIT("1e-400")) == 0.0);
	CHECK(iec_string_to_lreal(IEC_SLIT("4.9406564584124654e-324")) ==
	      5e-324);
	CHECK(isnan_(iec_string_to_lreal(IEC_SLIT("NaN"))));
	CHECK(iec_string_to_lreal(IEC_SLIT("-inf")) == -INF);
	CHECK(iec_string_to_lreal(IEC_SLIT("1.5x")) == 0.0);
	CHECK(iec_string_to_lreal(IEC_SLIT("")) == 0.0);
	CHECK(iec_string_to_lreal(IEC_SLIT(".5")) == 0.0);
	CHECK(iec_string_to_lreal(IEC_SLIT("12")) == 12.0);
	CHECK(same(iec_string_to_lreal(IEC_SLIT("-0.0")), -0.0));
	CHECK(iec_wstring_to_lreal(IEC_WSLIT(u"2.5E-1")) == 0.25);
	CHECK_DONE();
}
