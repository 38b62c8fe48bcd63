/* SPDX-License-Identifier: GPL-2.0-only OR MIT */
/*
 * Standard FBs under the sanitizers: fixed scenarios plus random traces with
 * extreme PT/PV/CV values and clock wraps (exactness against the reference
 * models is checked in test_rt_fb.py).
 */
#include "iec_std_fb.h"
#include "check.h"

static unsigned long long rng = 88172645463325252ull;

static unsigned long long rnd(void)
{
	rng ^= rng << 13;
	rng ^= rng >> 7;
	rng ^= rng << 17;
	return rng;
}

static long long pick(void)
{
	static const long long v[] = {
		0, 1, -1, 2, 50, IEC_S64_MAX, IEC_S64_MIN, IEC_S64_MAX - 1,
		IEC_S64_MIN + 1, 1000000000,
	};
	unsigned long long r = rnd();

	return r & 1 ? (long long)rnd() : v[(r >> 1) % 10];
}

int main(void)
{
	struct iec_ctx ctx;
	struct iec_fb_ton ton = { 0 };
	struct iec_fb_tof tof = { 0 };
	struct iec_fb_tp tp = { 0 };
	struct iec_fb_ctu ctu = { 0 };
	struct iec_fb_ctud_ulint ctud = { 0 };
	struct iec_fb_ctd_lint ctd = { 0 };
	struct iec_fb_ctud_udint ctud32 = { 0 };
	struct iec_fb_f_trig ft = { 0 };
	int i;

	iec_ctx_init(&ctx, 0);

	/* PT = 0: TON fires on the first TRUE call, TP never pulses */
	ton.in = 1;
	iec_fb_ton(&ton, &ctx);
	CHECK(ton.q && ton.et == 0);
	tp.in = 1;
	iec_fb_tp(&tp, &ctx);
	CHECK(!tp.q && tp.et == 0);
	/* TOF with PT = 0 falls on the call IN falls */
	tof.in = 1;
	iec_fb_tof(&tof, &ctx);
	CHECK(tof.q);
	tof.in = 0;
	iec_fb_tof(&tof, &ctx);
	CHECK(!tof.q && tof.et == 0);

	/* a huge PT across the wrap of the clock */
	iec_fb_ton_init(&ton);
	ton.in = 1;
	ton.pt = IEC_S64_MAX;
	ctx.now_ns = IEC_S64_MAX;
	iec_fb_ton(&ton, &ctx);
	ctx.now_ns = IEC_S64_MIN + 5;	/* 6 ns later */
	iec_fb_ton(&ton, &ctx);
	CHECK(!ton.q && ton.et == 6);

	/* F_TRIG reports no edge on the first call */
	iec_fb_f_trig(&ft, &ctx);
	CHECK(!ft.q);
	ft.clk = 1;
	iec_fb_f_trig(&ft, &ctx);
	ft.clk = 0;
	iec_fb_f_trig(&ft, &ctx);
	CHECK(ft.q);

	/* counters stop at their limits */
	ctu.cv = IEC_S16_MAX;
	ctu.cu = 1;
	iec_fb_ctu(&ctu, &ctx);
	CHECK_I(ctu.cv, IEC_S16_MAX);
	ctud.cd = 1;
	iec_fb_ctud_ulint(&ctud, &ctx);
	CHECK_U(ctud.cv, 0);
	CHECK(ctud.qd);
	ctd.cv = IEC_S64_MIN;
	ctd.cd = 1;
	iec_fb_ctd_lint(&ctd, &ctx);
	CHECK_I(ctd.cv, IEC_S64_MIN);

	for (i = 0; i < 200000; i++) {
		unsigned long long r = rnd();

		ctx.now_ns = (r & 7) ? (long long)((unsigned long long)ctx.now_ns +
						   (rnd() % 100)) : pick();
		ton.in = r >> 8 & 1;
		tof.in = r >> 9 & 1;
		tp.in = r >> 10 & 1;
		if ((r >> 11 & 15) == 0) {
			ton.pt = pick();
			tof.pt = pick();
			tp.pt = pick();
		}
		iec_fb_ton(&ton, &ctx);
		iec_fb_tof(&tof, &ctx);
		iec_fb_tp(&tp, &ctx);
		if (ton.et < 0 || tof.et < 0 || tp.et < 0)
			CHECK(0);

		ctd.cd = r >> 16 & 1;
		ctd.ld = (r >> 17 & 7) == 0;
		ctd.pv = pick();
		iec_fb_ctd_lint(&ctd, &ctx);
		ctud32.cu = r >> 20 & 1;
		ctud32.cd = r >> 21 & 1;
		ctud32.ld = (r >> 22 & 7) == 0;
		ctud32.r = (r >> 25 & 7) == 0;
		ctud32.pv = (iec_udint)pick();
		iec_fb_ctud_udint(&ctud32, &ctx);
		ctu.cu = r >> 28 & 1;
		ctu.r = (r >> 29 & 15) == 0;
		ctu.pv = (iec_int)pick();
		iec_fb_ctu(&ctu, &ctx);
	}
	CHECK(1);
	CHECK_DONE();
}
