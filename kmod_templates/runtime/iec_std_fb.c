// SPDX-License-Identifier: GPL-2.0-only OR MIT
/*
 * iec_std_fb.c - bodies of the standard function blocks (see
 * iec_std_fb.h for the semantics).
 */
#include "iec_std_fb.h"

void iec_fb_sr(struct iec_fb_sr *self, struct iec_ctx *ctx)
{
	(void)ctx;
	self->q1 = self->s1 || (!self->r && self->q1);
}

void iec_fb_rs(struct iec_fb_rs *self, struct iec_ctx *ctx)
{
	(void)ctx;
	self->q1 = !self->r1 && (self->s || self->q1);
}

void iec_fb_r_trig(struct iec_fb_r_trig *self, struct iec_ctx *ctx)
{
	(void)ctx;
	self->q = self->clk && !self->prev;
	self->prev = !!self->clk;
}

void iec_fb_f_trig(struct iec_fb_f_trig *self, struct iec_ctx *ctx)
{
	(void)ctx;
	self->q = !self->clk && self->prev;
	self->prev = !!self->clk;
}

/* Counters.  PVMAX/PVMIN are the limits of the counter's type. */
#define IEC__DEF_COUNTERS(n, T, PVMIN, PVMAX)				\
void iec_fb_ctu##n(struct iec_fb_ctu##n *self, struct iec_ctx *ctx)	\
{									\
	bool up = self->cu && !self->cu_prev;				\
									\
	(void)ctx;							\
	self->cu_prev = !!self->cu;					\
	if (self->r)							\
		self->cv = 0;						\
	else if (up && self->cv < (PVMAX))				\
		self->cv++;						\
	self->q = self->cv >= self->pv;					\
}									\
void iec_fb_ctd##n(struct iec_fb_ctd##n *self, struct iec_ctx *ctx)	\
{									\
	bool down = self->cd && !self->cd_prev;				\
									\
	(void)ctx;							\
	self->cd_prev = !!self->cd;					\
	if (self->ld)							\
		self->cv = self->pv;					\
	else if (down && self->cv > (PVMIN))				\
		self->cv--;						\
	self->q = self->cv <= 0;					\
}									\
void iec_fb_ctud##n(struct iec_fb_ctud##n *self, struct iec_ctx *ctx)	\
{									\
	bool up = self->cu && !self->cu_prev;				\
	bool down = self->cd && !self->cd_prev;				\
									\
	(void)ctx;							\
	self->cu_prev = !!self->cu;					\
	self->cd_prev = !!self->cd;					\
	if (self->r) {							\
		self->cv = 0;						\
	} else if (self->ld) {						\
		self->cv = self->pv;					\
	} else if (!(up && down)) {					\
		if (up && self->cv < (PVMAX))				\
			self->cv++;					\
		else if (down && self->cv > (PVMIN))			\
			self->cv--;					\
	}								\
	self->qu = self->cv >= self->pv;				\
	self->qd = self->cv <= 0;					\
}

IEC__DEF_COUNTERS(, iec_int, IEC_S16_MIN, IEC_S16_MAX)
IEC__DEF_COUNTERS(_int, iec_int, IEC_S16_MIN, IEC_S16_MAX)
IEC__DEF_COUNTERS(_dint, iec_dint, IEC_S32_MIN, IEC_S32_MAX)
IEC__DEF_COUNTERS(_lint, iec_lint, IEC_S64_MIN, IEC_S64_MAX)
IEC__DEF_COUNTERS(_udint, iec_udint, 0U, IEC_U32_MAX)
IEC__DEF_COUNTERS(_ulint, iec_ulint, 0ULL, IEC_U64_MAX)

/*
 * Timer cores.  Elapsed time is an unsigned 64-bit difference of the cycle
 * start times, correct across a wrap of the clock.  pt is >= 0.
 */
struct iec__timer {
	iec_bool in;
	iec_s64 pt;
	iec_bool q;
	iec_s64 et;
	iec_u8 state;
	iec_bool prev_in;
	iec_s64 start;
};

static iec_u64 iec__elapsed(const struct iec__timer *t, iec_s64 now)
{
	return (iec_u64)now - (iec_u64)t->start;
}

static void iec__ton(struct iec__timer *t, iec_s64 now)
{
	iec_u64 el;

	if (!t->in) {
		t->state = IEC_TIMER_INIT;
		t->q = 0;
		t->et = 0;
		return;
	}
	if (t->state != IEC_TIMER_WORK && t->state != IEC_TIMER_TOUT) {
		t->state = IEC_TIMER_WORK;
		t->start = now;
	}
	if (t->state == IEC_TIMER_WORK) {
		el = iec__elapsed(t, now);
		if (el < (iec_u64)t->pt) {
			t->q = 0;
			t->et = (iec_s64)el;
			return;
		}
		t->state = IEC_TIMER_TOUT;
	}
	t->q = 1;
	t->et = t->pt;
}

static void iec__tof(struct iec__timer *t, iec_s64 now)
{
	iec_u64 el;

	if (t->in) {
		t->state = IEC_TIMER_ON;
		t->q = 1;
		t->et = 0;
		return;
	}
	if (t->state == IEC_TIMER_ON) {
		t->state = IEC_TIMER_WORK;
		t->start = now;
	}
	if (t->state == IEC_TIMER_WORK) {
		el = iec__elapsed(t, now);
		if (el < (iec_u64)t->pt) {
			t->q = 1;
			t->et = (iec_s64)el;
			return;
		}
		t->state = IEC_TIMER_TOUT;
	}
	t->q = 0;
	t->et = t->state == IEC_TIMER_TOUT ? t->pt : 0;
}

static void iec__tp(struct iec__timer *t, iec_s64 now)
{
	iec_u64 el;
	bool rising = t->in && !t->prev_in;

	t->prev_in = !!t->in;
	if (t->state != IEC_TIMER_WORK && rising) {
		t->state = IEC_TIMER_WORK;
		t->start = now;
	}
	if (t->state == IEC_TIMER_WORK) {
		el = iec__elapsed(t, now);
		if (el < (iec_u64)t->pt) {
			t->q = 1;
			t->et = (iec_s64)el;
			return;
		}
		t->state = IEC_TIMER_TOUT;
	}
	if (!t->in)
		t->state = IEC_TIMER_INIT;
	t->q = 0;
	t->et = t->state == IEC_TIMER_TOUT ? t->pt : 0;
}

#define IEC__DEF_TIMER(n, core)						\
void iec_fb_##n(struct iec_fb_##n *self, struct iec_ctx *ctx)		\
{									\
	struct iec__timer t = {						\
		.in = self->in,						\
		.pt = self->pt < 0 ? 0 : self->pt,			\
		.state = self->state,					\
		.prev_in = self->prev_in,				\
		.start = self->start,					\
	};								\
									\
	core(&t, ctx->now_ns);						\
	self->q = t.q;							\
	self->et = t.et;						\
	self->state = t.state;						\
	self->prev_in = t.prev_in;					\
	self->start = t.start;						\
}

IEC__DEF_TIMER(tp, iec__tp)
IEC__DEF_TIMER(ton, iec__ton)
IEC__DEF_TIMER(tof, iec__tof)
IEC__DEF_TIMER(tp_ltime, iec__tp)
IEC__DEF_TIMER(ton_ltime, iec__ton)
IEC__DEF_TIMER(tof_ltime, iec__tof)

void iec_fb_rtc(struct iec_fb_rtc *self, struct iec_ctx *ctx)
{
	iec_u64 now = (iec_u64)ctx->wall_ns;

	if (self->in) {
		if (!self->prev_in)
			self->offset = (iec_s64)((iec_u64)self->pdt - now);
		self->cdt = (iec_dt)(now + (iec_u64)self->offset);
	} else {
		self->cdt = (iec_dt)now;
	}
	self->q = !!self->in;
	self->prev_in = !!self->in;
}

static void iec__action_timer(struct iec_fb_ton *tmr, iec_bool in, iec_time pt,
			      struct iec_ctx *ctx)
{
	tmr->in = in;
	tmr->pt = pt;
	iec_fb_ton(tmr, ctx);
}

void iec_fb_action_control(struct iec_fb_action_control *self, struct iec_ctx *ctx)
{
	iec_bool p_q, p1_q, p0_q;

	self->s_ff = !self->r && (self->s0 || self->s_ff);
	iec__action_timer(&self->l_tmr, self->l, self->t, ctx);
	iec__action_timer(&self->d_tmr, self->d, self->t, ctx);
	p_q = self->p && !self->p_prev;
	self->p_prev = !!self->p;
	p1_q = self->p1 && !self->p1_prev;
	self->p1_prev = !!self->p1;
	p0_q = !self->p0 && self->p0_prev;
	self->p0_prev = !!self->p0;
	self->sd_ff = !self->r && (self->sd || self->sd_ff);
	iec__action_timer(&self->sd_tmr, self->sd_ff, self->t, ctx);
	iec__action_timer(&self->ds_tmr, self->ds, self->t, ctx);
	self->ds_ff = !self->r && (self->ds_tmr.q || self->ds_ff);
	self->sl_ff = !self->r && (self->sl || self->sl_ff);
	iec__action_timer(&self->sl_tmr, self->sl_ff, self->t, ctx);
	self->q = !self->r &&
		  (self->n || self->s_ff || (self->l && !self->l_tmr.q) || self->d_tmr.q ||
		   p_q || self->sd_tmr.q || self->ds_ff || (self->sl_ff && !self->sl_tmr.q));
	self->a = self->q || p1_q || p0_q;
}
