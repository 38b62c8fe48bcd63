// SPDX-License-Identifier: MIT
/*
 * scan_cost.py, benchmark 1: the interlock of interlock.st written by hand,
 * as a careful C programmer would: same inputs, outputs and state, same
 * results cycle by cycle.
 */
#include "hand.h"

struct hand_interlock {
	bool estop_ok, guard_closed, curtain_clear, two_hand_l, two_hand_r;
	bool pump_feedback, pressure_ok, oil_temp_ok, top_limit, bottom_limit;
	bool mode_auto, mode_setup, ack, start_pb, stop_pb;
	bool pump_on, valve_down, valve_up, lamp_ready, lamp_fault, horn;
	uint16_t fault_code;
	bool stroke_down, start_prev, ack_prev, running;
	bool f_pump, f_pressure, f_temp, f_curtain;
};

void hand_interlock_body(struct hand_interlock *s, struct hand_ctx *ctx)
{
	bool safe = s->estop_ok && s->guard_closed && (s->curtain_clear || s->mode_setup);
	bool two_hand = s->two_hand_l && s->two_hand_r;
	bool start_edge = s->start_pb && !s->start_prev;
	bool ack_edge = s->ack && !s->ack_prev;
	bool fault_latched, set, reset;

	(void)ctx;
	s->start_prev = s->start_pb;
	s->ack_prev = s->ack;
	if (s->pump_on && !s->pump_feedback)
		s->f_pump = true;
	if (s->pump_on && s->pump_feedback && !s->pressure_ok)
		s->f_pressure = true;
	if (!s->oil_temp_ok)
		s->f_temp = true;
	if (s->stroke_down && !s->curtain_clear && !s->mode_setup)
		s->f_curtain = true;
	if (ack_edge && safe)
		s->f_pump = s->f_pressure = s->f_temp = s->f_curtain = false;
	fault_latched = s->f_pump || s->f_pressure || s->f_temp || s->f_curtain;

	set = start_edge && safe && !fault_latched;
	reset = s->stop_pb || !safe || fault_latched;
	s->running = set || (!reset && s->running);	/* SR: set dominant */
	s->pump_on = s->running;

	if (s->running && two_hand && s->mode_auto && !s->bottom_limit)
		s->stroke_down = true;
	else if (s->bottom_limit || !two_hand || !s->running)
		s->stroke_down = false;
	s->valve_down = s->stroke_down && safe && !s->valve_up;
	s->valve_up = !s->stroke_down && s->running && !s->top_limit;

	s->lamp_ready = safe && !fault_latched && !s->running;
	s->lamp_fault = fault_latched;
	s->horn = fault_latched && !s->ack;
	s->fault_code = (uint16_t)(s->f_pump | s->f_pressure << 1 | s->f_temp << 2 |
				   s->f_curtain << 3 | !s->estop_ok << 15);
}
