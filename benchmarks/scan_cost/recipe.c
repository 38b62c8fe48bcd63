// SPDX-License-Identifier: MIT
/*
 * scan_cost.py, benchmark 3: the recipe handler of recipe.st written by
 * hand in C with the same semantics: bounded strings that truncate, INT
 * arithmetic that wraps, array indexes checked (a bad index is a fault of
 * the task, as in IEC), the same status text.
 */
#include "hand.h"

#define NAME_LEN 16
#define STATUS_LEN 48

struct str16 {
	uint16_t len;
	char data[NAME_LEN + 1];
};

struct str48 {
	uint16_t len;
	char data[STATUS_LEN + 1];
};

struct recipe_rec {
	struct str16 name;
	int16_t amounts[6];
	int16_t mix_time[6];
};

struct hand_recipe {
	struct str16 request;
	bool step_done;
	int16_t scale;
	struct str16 active_name;
	struct str48 status;
	int16_t dose;
	int32_t total;
	bool found;
	int16_t step;
	struct recipe_rec book[8];
	int16_t active[6];
	int16_t steps_used;
	bool prev_done;
};

static bool str_eq(const struct str16 *a, const struct str16 *b)
{
	return a->len == b->len && memcmp(a->data, b->data, a->len) == 0;
}

/* append n bytes, truncating at the capacity */
static void append(struct str48 *s, const char *p, unsigned int n)
{
	unsigned int room = STATUS_LEN - s->len;

	if (n > room)
		n = room;
	memcpy(s->data + s->len, p, n);
	s->len = (uint16_t)(s->len + n);
	s->data[s->len] = 0;
}

static void append_int(struct str48 *s, int v)
{
	char buf[8];
	unsigned int n = 0, u = v < 0 ? 0u - (unsigned int)v : (unsigned int)v;
	char *p = buf + sizeof(buf);

	do {
		*--p = (char)('0' + u % 10);
		u /= 10;
		n++;
	} while (u);
	if (v < 0) {
		*--p = '-';
		n++;
	}
	append(s, p, n);
}

static void set_name(struct recipe_rec *r, const char *name, const int16_t *amounts,
		     const int16_t *mix)
{
	r->name.len = (uint16_t)strlen(name);
	memcpy(r->name.data, name, r->name.len + 1);
	memcpy(r->amounts, amounts, sizeof(r->amounts));
	memcpy(r->mix_time, mix, sizeof(r->mix_time));
}

void hand_recipe_init(struct hand_recipe *s)
{
	static const int16_t a[8][6] = {
		{10, 20, 30, 0, 0, 0}, {12, 8, 4, 2, 0, 0}, {15, 5, 5, 5, 5, 0},
		{40, 10, 0, 0, 0, 0}, {35, 12, 3, 0, 0, 0}, {50, 0, 0, 0, 0, 0},
		{5, 5, 5, 5, 5, 5}, {60, 0, 0, 0, 0, 0} };
	static const int16_t m[8][6] = {
		{5, 5, 10, 0, 0, 0}, {3, 3, 3, 3, 0, 0}, {2, 2, 2, 2, 2, 0},
		{20, 10, 0, 0, 0, 0}, {15, 5, 5, 0, 0, 0}, {30, 0, 0, 0, 0, 0},
		{1, 1, 1, 1, 1, 1}, {60, 0, 0, 0, 0, 0} };
	static const char *const names[8] = { "BASE", "PRIMER-A", "PRIMER-B", "GLOSS",
					      "MATT", "SEALER", "THINNER", "CLEAN" };
	int i;

	memset(s, 0, sizeof(*s));
	for (i = 0; i < 8; i++)
		set_name(&s->book[i], names[i], a[i], m[i]);
}

void hand_recipe_body(struct hand_recipe *s, struct hand_ctx *ctx)
{
	int i;
	int32_t total = 0;

	if (!str_eq(&s->request, &s->active_name)) {
		int sel = -1;

		for (i = 0; i < 8; i++) {
			if (str_eq(&s->book[i].name, &s->request)) {
				sel = i;
				break;
			}
		}
		s->found = sel >= 0;
		if (s->found) {
			const struct recipe_rec *r = &s->book[sel];

			s->active_name = r->name;
			s->steps_used = 0;
			for (i = 0; i < 6; i++) {
				/* INT arithmetic wraps; the divisor is a constant */
				s->active[i] = (int16_t)((int16_t)(r->amounts[i] * s->scale) / 10);
				if (s->active[i] > 0)
					s->steps_used = (int16_t)(i + 1);
			}
			s->step = 1;
		} else {
			s->active_name.len = 0;
			s->active_name.data[0] = 0;
			s->steps_used = 0;
			s->step = 0;
		}
	}
	if (s->step_done && !s->prev_done && s->step > 0) {
		s->step = (int16_t)(s->step + 1);
		if (s->step > s->steps_used)
			s->step = 1;
	}
	s->prev_done = s->step_done;
	for (i = 0; i < 6; i++)
		total += s->active[i];
	s->total = total;
	s->status.len = 0;
	if (s->step > 0) {
		if (s->step > 6) {		/* index check: a fault of the task */
			ctx->fault = 2;
			ctx->fault_line = 81;
			return;
		}
		s->dose = s->active[s->step - 1];
		append(&s->status, s->active_name.data, s->active_name.len);
		append(&s->status, " step ", 6);
		append_int(&s->status, s->step);
		append(&s->status, "/", 1);
		append_int(&s->status, s->steps_used);
		append(&s->status, ": ", 2);
		append_int(&s->status, s->dose);
	} else {
		s->dose = 0;
		append(&s->status, "no recipe ", 10);
		append(&s->status, s->request.data, s->request.len < 8 ? s->request.len : 8);
	}
	s->status.data[s->status.len] = 0;
}
