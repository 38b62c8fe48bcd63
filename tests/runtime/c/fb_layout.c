/* SPDX-License-Identifier: GPL-2.0-only OR MIT */
/*
 * fb_layout.c - exported sizes and offsets of the FB and ctx structs, so
 * the ctypes mirrors in test_rt_fb.py are checked against the C layout.
 */
#include "iec_std_fb.h"

#define OFF(s, m) (long)__builtin_offsetof(struct s, m)

long iec_test_layout(const char *what);
long iec_test_layout(const char *what)
{
	static const struct {
		const char *name;
		long v;
	} t[] = {
		{ "ctx", sizeof(struct iec_ctx) },
		{ "ctx.now_ns", OFF(iec_ctx, now_ns) },
		{ "ctx.fault", OFF(iec_ctx, fault) },
		{ "ctx.fault_count", OFF(iec_ctx, fault_count) },
		{ "ctx.sel_skipped", OFF(iec_ctx, sel_skipped) },
		{ "ctx.frame_base", OFF(iec_ctx, frame_base) },
		{ "ctx.task_id", OFF(iec_ctx, task_id) },
		{ "ton", sizeof(struct iec_fb_ton) },
		{ "ton.pt", OFF(iec_fb_ton, pt) },
		{ "ton.q", OFF(iec_fb_ton, q) },
		{ "ton.et", OFF(iec_fb_ton, et) },
		{ "ton.state", OFF(iec_fb_ton, state) },
		{ "ton.start", OFF(iec_fb_ton, start) },
		{ "ctud_lint", sizeof(struct iec_fb_ctud_lint) },
		{ "ctud_lint.pv", OFF(iec_fb_ctud_lint, pv) },
		{ "ctud_lint.cv", OFF(iec_fb_ctud_lint, cv) },
		{ "ctud_lint.cd_prev", OFF(iec_fb_ctud_lint, cd_prev) },
		{ "ctud", sizeof(struct iec_fb_ctud) },
		{ "ctud.cv", OFF(iec_fb_ctud, cv) },
		{ "action_control", sizeof(struct iec_fb_action_control) },
		{ "action_control.t", OFF(iec_fb_action_control, t) },
		{ "action_control.q", OFF(iec_fb_action_control, q) },
		{ "action_control.a", OFF(iec_fb_action_control, a) },
		{ "action_control.p0_prev", OFF(iec_fb_action_control, p0_prev) },
		{ "action_control.l_tmr", OFF(iec_fb_action_control, l_tmr) },
		{ "action_control.sl_tmr", OFF(iec_fb_action_control, sl_tmr) },
	};
	unsigned int i;

	for (i = 0; i < sizeof(t) / sizeof(t[0]); i++) {
		const char *a = t[i].name, *b = what;

		while (*a && *a == *b) {
			a++;
			b++;
		}
		if (!*a && !*b)
			return t[i].v;
	}
	return -1;
}
