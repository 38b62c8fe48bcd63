// SPDX-License-Identifier: MIT
/*
 * scan_cost.py, benchmark 2: the PID of pid.st written by hand in C, same
 * REAL (float) arithmetic in the same order, so the results are identical.
 */
#include "hand.h"

struct hand_pid {
	float setpoint, measured;
	bool manual;
	float manual_out;
	float out, error;
	bool saturated;
	float kp, ti, td, td_filter, dt, out_min, out_max, ramp_rate, max_step;
	float sp_ramped, integral, deriv, prev_meas, prev_out;
	bool initialised;
	float unclamped;
};

static inline float limitf(float lo, float x, float hi)
{
	/* LIMIT = MIN(MAX(x, lo), hi), NaN-propagating like the IEC MAX/MIN */
	float m = x != x ? x : (lo != lo ? lo : (x >= lo ? x : lo));

	if (m != m)
		return m;
	if (hi != hi)
		return hi;
	return m <= hi ? m : hi;
}

void hand_pid_init(struct hand_pid *s)
{
	memset(s, 0, sizeof(*s));
	s->kp = 1.2f;
	s->ti = 8.0f;
	s->td = 0.5f;
	s->td_filter = 0.1f;
	s->dt = 0.01f;
	s->out_max = 100.0f;
	s->ramp_rate = 5.0f;
	s->max_step = 2.0f;
}

void hand_pid_body(struct hand_pid *s, struct hand_ctx *ctx)
{
	float step, p_part;

	(void)ctx;
	if (!s->initialised) {
		s->prev_meas = s->measured;
		s->sp_ramped = s->measured;
		s->initialised = true;
	}
	step = s->ramp_rate * s->dt;
	s->sp_ramped = limitf(s->sp_ramped - step, s->setpoint, s->sp_ramped + step);
	s->error = s->sp_ramped - s->measured;
	p_part = s->kp * s->error;
	if (s->td > 0.0f && s->dt > 0.0f) {
		float alpha = s->dt / (s->td_filter + s->dt);

		s->deriv = s->deriv + alpha * (-s->kp * s->td * (s->measured - s->prev_meas) /
					       s->dt - s->deriv);
	} else {
		s->deriv = 0.0f;
	}
	s->prev_meas = s->measured;
	if (s->manual) {
		float m = limitf(s->out_min, s->manual_out, s->out_max);

		s->integral = m - p_part - s->deriv;
		s->out = m;
	} else {
		if (s->ti > 0.0f) {
			s->integral = s->integral + s->kp * s->dt / s->ti * s->error;
			s->integral = limitf(s->out_min - p_part - s->deriv, s->integral,
					     s->out_max - p_part - s->deriv);
		} else {
			s->integral = 0.0f;
		}
		s->unclamped = p_part + s->integral + s->deriv;
		s->out = limitf(s->out_min, s->unclamped, s->out_max);
		s->out = limitf(s->prev_out - s->max_step, s->out, s->prev_out + s->max_step);
	}
	s->saturated = s->out != s->unclamped;
	s->prev_out = s->out;
}
