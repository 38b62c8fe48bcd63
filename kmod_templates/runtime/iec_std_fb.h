/* SPDX-License-Identifier: GPL-2.0-only OR MIT */
/*
 * iec_std_fb.h - the standard function blocks.
 *
 * An FB type is a struct (inputs, outputs, then internal state, member
 * names are the IEC names in lower case) and a body:
 *
 *   struct iec_fb_<name> inst;            TON -> struct iec_fb_ton
 *   void iec_fb_<name>(struct iec_fb_<name> *self, struct iec_ctx *ctx);
 *
 * A call  t1(IN := x, PT := T#5s);  is emitted as
 *   t1.in = x; t1.pt = 5000000000; iec_fb_ton(&t1, ctx);
 * and outputs are read from the struct afterwards (t1.q, t1.et).
 *
 * The all-zero struct is every FB's initial state (CV = 0, Q = FALSE,
 * timers idle), so instances in zero-initialised storage need no init
 * call; iec_fb_<name>_init() exists for re-initialisation and sets zero.
 *
 * FBs:
 *   SR, RS                  bistables (set / reset dominant)
 *   R_TRIG, F_TRIG          edge detectors.  F_TRIG's memory starts as
 *                           "CLK was FALSE", so no edge is reported on the
 *                           first call (the ed.2 text initialises M so that
 *                           a FALSE CLK on the first call gives Q = TRUE;
 *                           the runtime follows ed.3 practice instead).
 *   CTU, CTD, CTUD          INT counters; _INT, _DINT, _LINT, _UDINT,
 *                           _ULINT variants (CTU_DINT -> iec_fb_ctu_dint).
 *                           CV never passes the type's limits (PVmax,
 *                           PVmin); CTD/CTUD: Q/QD = (CV <= 0).
 *   TP, TON, TOF            timers; _LTIME variants are the same with LTIME.
 *
 * Timers read ctx->now_ns (the cycle start) and work on unsigned 64-bit
 * differences, so the clock may wrap.  A negative PT acts as T#0s.  PT is
 * read at every call.  Each timer is one of the automaton states of the
 * reference model: Init (ET = 0), Work (0 <= ET < PT, timing), Tout
 * (ET = PT):
 *   TON  IN FALSE -> Init: Q = FALSE, ET = 0.  IN TRUE in Init -> Work,
 *        timing from this call.  Work: ET = elapsed; once elapsed >= PT ->
 *        Tout: Q = TRUE, ET = PT, until IN is FALSE.  PT = 0 gives Q on
 *        the call IN is first TRUE.
 *   TOF  IN TRUE -> Q = TRUE, ET = 0.  IN FALSE after TRUE -> Work,
 *        Q stays TRUE, ET = elapsed; once elapsed >= PT -> Tout: Q = FALSE,
 *        ET = PT until IN is TRUE again.  Initially Q = FALSE, ET = 0.
 *   TP   a rising edge of IN seen while not timing starts a pulse: Work,
 *        Q = TRUE, ET = elapsed, not retriggerable.  When elapsed >= PT
 *        the pulse ends (Q = FALSE): ET = PT while IN stays TRUE (Tout),
 *        ET = 0 once IN is FALSE (Init; also on the call the pulse ends if
 *        IN is FALSE then).  PT = 0 gives no pulse.
 * IN pulses shorter than a cycle are only seen if a call sees them.
 *   RTC  (ed.1 table 35, as MatIEC defines it) Q = IN.  A rising IN sets
 *        the clock: offset = PDT - clock; while IN stays TRUE, CDT = clock
 *        + offset (PDT changed meanwhile is not taken); IN FALSE: CDT =
 *        clock.  The clock is ctx->wall_ns: the wall clock at the cycle's
 *        release in the kernel, the simulated time from DT#1970-01-01 in
 *        the simulator.  DT arithmetic wraps (unsigned 64-bit).
 */
#ifndef IEC_STD_FB_H
#define IEC_STD_FB_H

#include "iec_fault.h"

/* Timer automaton states (struct member "state"). */
enum iec_timer_state {
	IEC_TIMER_INIT = 0,
	IEC_TIMER_WORK = 1,
	IEC_TIMER_TOUT = 2,
	IEC_TIMER_ON = 3,	/* TOF only: IN is TRUE */
};

struct iec_fb_sr {
	iec_bool s1;
	iec_bool r;
	iec_bool q1;
};

struct iec_fb_rs {
	iec_bool s;
	iec_bool r1;
	iec_bool q1;
};

struct iec_fb_r_trig {
	iec_bool clk;
	iec_bool q;
	iec_bool prev;		/* CLK of the previous call (standard: M) */
};

struct iec_fb_f_trig {
	iec_bool clk;
	iec_bool q;
	iec_bool prev;		/* CLK of the previous call (standard: NOT M) */
};

#define IEC__DECL_COUNTERS(n, T)					\
struct iec_fb_ctu##n {							\
	iec_bool cu;							\
	iec_bool r;							\
	T pv;								\
	iec_bool q;							\
	T cv;								\
	iec_bool cu_prev;						\
};									\
struct iec_fb_ctd##n {							\
	iec_bool cd;							\
	iec_bool ld;							\
	T pv;								\
	iec_bool q;							\
	T cv;								\
	iec_bool cd_prev;						\
};									\
struct iec_fb_ctud##n {							\
	iec_bool cu;							\
	iec_bool cd;							\
	iec_bool r;							\
	iec_bool ld;							\
	T pv;								\
	iec_bool qu;							\
	iec_bool qd;							\
	T cv;								\
	iec_bool cu_prev;						\
	iec_bool cd_prev;						\
};									\
void iec_fb_ctu##n(struct iec_fb_ctu##n *self, struct iec_ctx *ctx);	\
void iec_fb_ctd##n(struct iec_fb_ctd##n *self, struct iec_ctx *ctx);	\
void iec_fb_ctud##n(struct iec_fb_ctud##n *self, struct iec_ctx *ctx);	\
static inline void iec_fb_ctu##n##_init(struct iec_fb_ctu##n *self)	\
{									\
	iec_memset(self, 0, sizeof(*self));				\
}									\
static inline void iec_fb_ctd##n##_init(struct iec_fb_ctd##n *self)	\
{									\
	iec_memset(self, 0, sizeof(*self));				\
}									\
static inline void iec_fb_ctud##n##_init(struct iec_fb_ctud##n *self)	\
{									\
	iec_memset(self, 0, sizeof(*self));				\
}

IEC__DECL_COUNTERS(, iec_int)
IEC__DECL_COUNTERS(_int, iec_int)
IEC__DECL_COUNTERS(_dint, iec_dint)
IEC__DECL_COUNTERS(_lint, iec_lint)
IEC__DECL_COUNTERS(_udint, iec_udint)
IEC__DECL_COUNTERS(_ulint, iec_ulint)

#define IEC__DECL_TIMER(n, T)						\
struct iec_fb_##n {							\
	iec_bool in;							\
	T pt;								\
	iec_bool q;							\
	T et;								\
	iec_u8 state;		/* enum iec_timer_state */		\
	iec_bool prev_in;	/* TP: IN of the previous call */	\
	iec_s64 start;		/* ctx->now_ns when timing started */	\
};									\
void iec_fb_##n(struct iec_fb_##n *self, struct iec_ctx *ctx);		\
static inline void iec_fb_##n##_init(struct iec_fb_##n *self)		\
{									\
	iec_memset(self, 0, sizeof(*self));				\
}

IEC__DECL_TIMER(tp, iec_time)
IEC__DECL_TIMER(ton, iec_time)
IEC__DECL_TIMER(tof, iec_time)
IEC__DECL_TIMER(tp_ltime, iec_ltime)
IEC__DECL_TIMER(ton_ltime, iec_ltime)
IEC__DECL_TIMER(tof_ltime, iec_ltime)

struct iec_fb_rtc {
	iec_bool in;
	iec_dt pdt;
	iec_bool q;
	iec_dt cdt;
	iec_bool prev_in;	/* IN of the previous call */
	iec_s64 offset;		/* PDT - clock at the rising IN */
};

void iec_fb_rtc(struct iec_fb_rtc *self, struct iec_ctx *ctx);

static inline void iec_fb_rtc_init(struct iec_fb_rtc *self)
{
	iec_memset(self, 0, sizeof(*self));
}

/*
 * ACTION_CONTROL (IEC 61131-3 ed.2 2.6.4.5, figure 14, the form without
 * final scan): the control of one SFC action.  Each Boolean input is the
 * OR of the activity flags (X) of the steps that associate the action with
 * that qualifier; T is the time of the timed association in force.  Q is
 * the action flag (a Boolean-variable action takes its value); A, the
 * activation, is Q or a P1/P0 pulse: an action's statements run while A
 * is TRUE (ed.2 2.6.4.5 rule 1 and its notes 2-3: Q stays FALSE during
 * an execution invoked by P1 or P0).  The body is the standard's network
 * of blocks, in its order:
 *   S_FF  RS(S := S0, R1 := R)       L_TMR  TON(IN := L, PT := T)
 *   D_TMR TON(IN := D, PT := T)      P_TRIG R_TRIG(CLK := P)
 *   P1_TRIG R_TRIG(CLK := P1)        P0_TRIG F_TRIG(CLK := P0)
 *   SD_FF RS(S := SD, R1 := R)       SD_TMR TON(IN := SD_FF.Q1, PT := T)
 *   DS_TMR TON(IN := DS, PT := T)    DS_FF  RS(S := DS_TMR.Q, R1 := R)
 *   SL_FF RS(S := SL, R1 := R)       SL_TMR TON(IN := SL_FF.Q1, PT := T)
 *   Q := NOT R AND (N OR S_FF.Q1 OR (L AND NOT L_TMR.Q) OR D_TMR.Q OR
 *        P_TRIG.Q OR SD_TMR.Q OR DS_FF.Q1 OR (SL_FF.Q1 AND NOT SL_TMR.Q))
 *   A := Q OR P1_TRIG.Q OR P0_TRIG.Q
 * The timers are the TON above (ctx->now_ns, PT read at every call).  The
 * all-zero struct is the initial state (F_TRIG: "CLK was FALSE").
 */
struct iec_fb_action_control {
	iec_bool n, r, s0, l, d, p, p1, p0, sd, ds, sl;
	iec_time t;
	iec_bool q, a;
	iec_bool s_ff, sd_ff, ds_ff, sl_ff;	/* the RS blocks' Q1 */
	iec_bool p_prev, p1_prev, p0_prev;	/* the edge detectors' memories */
	struct iec_fb_ton l_tmr, d_tmr, sd_tmr, ds_tmr, sl_tmr;
};

void iec_fb_action_control(struct iec_fb_action_control *self, struct iec_ctx *ctx);

static inline void iec_fb_action_control_init(struct iec_fb_action_control *self)
{
	iec_memset(self, 0, sizeof(*self));
}

void iec_fb_sr(struct iec_fb_sr *self, struct iec_ctx *ctx);
void iec_fb_rs(struct iec_fb_rs *self, struct iec_ctx *ctx);
void iec_fb_r_trig(struct iec_fb_r_trig *self, struct iec_ctx *ctx);
void iec_fb_f_trig(struct iec_fb_f_trig *self, struct iec_ctx *ctx);

static inline void iec_fb_sr_init(struct iec_fb_sr *self)
{
	iec_memset(self, 0, sizeof(*self));
}

static inline void iec_fb_rs_init(struct iec_fb_rs *self)
{
	iec_memset(self, 0, sizeof(*self));
}

static inline void iec_fb_r_trig_init(struct iec_fb_r_trig *self)
{
	iec_memset(self, 0, sizeof(*self));
}

static inline void iec_fb_f_trig_init(struct iec_fb_f_trig *self)
{
	iec_memset(self, 0, sizeof(*self));
}

#endif /* IEC_STD_FB_H */
