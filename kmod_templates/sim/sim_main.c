// SPDX-License-Identifier: GPL-2.0-only OR MIT
/*
 * sim_main.c - the host simulator's scheduler (iec2kmod sim).
 *
 * Runs the generated POU C against a simulated clock, deterministically:
 * every periodic task is released at 0, INTERVAL, 2*INTERVAL ...; an event
 * task runs when its SINGLE variable rises (checked after inputs are
 * applied and after every task cycle).  Tasks released at the same instant
 * run in IEC priority order (0 first), ties in declaration order; a cycle
 * runs to completion (execution takes no time on the clock that releases
 * the tasks).  A task that faults stops; the others go on.
 *
 * The watchdog (iec2kmod/checks/tasks.py) runs on simulated execution
 * time: SIM_ITERATION_NS per loop iteration, nothing else.  A cycle gets
 * only the iterations that fit in its watchdog time (the budget, then
 * faulting with IEC_FAULT_WATCHDOG); a cycle whose iterations take longer
 * than the task's interval is an overrun, and watchdog_overruns of them in
 * a row fault the task (IEC_FAULT_OVERRUN, its results not written).
 *
 * Protocol (the Python driver writes argv and the events file):
 *   sim END_NS EVENTS_FILE WATCH_INDEX...
 *   events file lines: "<t_ns> <var index> i <int>" | "... f <double>" |
 *                      "... s <hex bytes>"
 *   stdout: "v <t_ns> <index> <value>" when a watched variable changes,
 *           "f <t_ns> <task> <fault name>|<pou>|<file>|<line>" on a fault,
 *           "n <task> <cycles>" per task at the end.
 *
 * This file is user-space only; it may use libc.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <stdint.h>
#include <inttypes.h>

#include "sim.h"

#define SIM_ITERATION_NS 100LL	/* iec2kmod/execmodel.py SIM_ITERATION_NS */

struct event {
	long long t;
	int var;
	char kind;
	long long i;
	double f;
	char *s;
	unsigned int slen;
};

static struct event *events;
static int nevents, next_event;
static long long *last_int;
static double *last_f;
static char **last_s;
static unsigned char *seen;

static void die(const char *msg)
{
	fprintf(stderr, "sim: %s\n", msg);
	exit(2);
}

static int hexval(int c)
{
	if (c >= '0' && c <= '9')
		return c - '0';
	if (c >= 'a' && c <= 'f')
		return c - 'a' + 10;
	if (c >= 'A' && c <= 'F')
		return c - 'A' + 10;
	return -1;
}

static void load_events(const char *path)
{
	FILE *fp = fopen(path, "r");
	char line[8192];
	int cap = 0;

	if (!fp)
		die("cannot open the events file");
	while (fgets(line, sizeof(line), fp)) {
		struct event ev = { 0 };
		char kind;
		int off = 0;

		if (sscanf(line, "%lld %d %c %n", &ev.t, &ev.var, &kind, &off) < 3)
			continue;
		if (ev.var < 0 || ev.var >= sim_nvars)
			die("event for an unknown variable");
		ev.kind = kind;
		if (kind == 'i' && sim_vars[ev.var].kind == 'u') {
			/* ULINT/LWORD: 2^63 and more do not fit a long long */
			ev.i = (long long)strtoull(line + off, NULL, 10);
		} else if (kind == 'i') {
			ev.i = strtoll(line + off, NULL, 10);
		} else if (kind == 'f') {
			ev.f = strtod(line + off, NULL);
		} else if (kind == 's') {
			const char *h = line + off;
			unsigned int n = 0;

			ev.s = malloc(strlen(h) / 2 + 1);
			if (!ev.s)
				die("out of memory");
			while (hexval(h[0]) >= 0 && hexval(h[1]) >= 0) {
				ev.s[n++] = (char)(hexval(h[0]) * 16 + hexval(h[1]));
				h += 2;
			}
			ev.slen = n;
		} else {
			die("bad event kind");
		}
		if (nevents == cap) {
			cap = cap ? 2 * cap : 64;
			events = realloc(events, sizeof(*events) * (size_t)cap);
			if (!events)
				die("out of memory");
		}
		events[nevents++] = ev;
	}
	fclose(fp);
}

static long long get_int(const struct sim_var *v)
{
	switch (v->kind) {
	case 'b':
	case 'u':
		switch (v->size) {
		case 1: return *(uint8_t *)v->addr;
		case 2: return *(uint16_t *)v->addr;
		case 4: return *(uint32_t *)v->addr;
		default: return (long long)*(uint64_t *)v->addr;
		}
	default:
		switch (v->size) {
		case 1: return *(int8_t *)v->addr;
		case 2: return *(int16_t *)v->addr;
		case 4: return *(int32_t *)v->addr;
		default: return *(int64_t *)v->addr;
		}
	}
}

static void set_int(const struct sim_var *v, long long x)
{
	switch (v->size) {
	case 1: *(uint8_t *)v->addr = (uint8_t)x; break;
	case 2: *(uint16_t *)v->addr = (uint16_t)x; break;
	case 4: *(uint32_t *)v->addr = (uint32_t)x; break;
	default: *(uint64_t *)v->addr = (uint64_t)x; break;
	}
}

static double get_f(const struct sim_var *v)
{
	return v->size == 4 ? *(float *)v->addr : *(double *)v->addr;
}

/*
 * Selective execution (iec2kmod sim --selective): the generated table
 * sim_sel_owned marks the variables that live in program instances; an
 * input event into one bumps the epoch every task's blocks compare with
 * (a write the blocks' argument sets do not see).  Plain builds define no
 * such table.
 */
extern const unsigned char sim_sel_owned[] __attribute__((weak));
static iec_u32 sim_sel_epoch;

static void apply(const struct event *ev)
{
	const struct sim_var *v = &sim_vars[ev->var];

	if (sim_sel_owned && sim_sel_owned[ev->var])
		sim_sel_epoch++;

	if (v->kind == 'f') {
		if (v->size == 4)
			*(float *)v->addr = (float)(ev->kind == 'f' ? ev->f : (double)ev->i);
		else
			*(double *)v->addr = ev->kind == 'f' ? ev->f : (double)ev->i;
	} else if (v->kind == 's' || v->kind == 'w') {
		die("string inputs are not supported by the simulator");
	} else {
		set_int(v, ev->kind == 'i' ? ev->i : (long long)ev->f);
	}
}

static void print_value(long long t, int idx, int force)
{
	const struct sim_var *v = &sim_vars[idx];

	if (v->kind == 'f') {
		double x = get_f(v);

		if (!force && seen[idx] && memcmp(&x, &last_f[idx], sizeof(x)) == 0)
			return;
		last_f[idx] = x;
		printf("v %lld %d %.17g\n", t, idx, x);
	} else if (v->kind == 's' || v->kind == 'w') {
		/* STRING: 2 hex digits per character, WSTRING: 4 */
		unsigned int len, i, digits = v->kind == 's' ? 2 : 4;
		char *hex;

		if (v->kind == 's')
			len = ((const struct iec_string *)v->addr)->len;
		else
			len = ((const struct iec_wstring *)v->addr)->len;
		hex = malloc((size_t)len * digits + 1);
		if (!hex)
			die("out of memory");
		for (i = 0; i < len; i++) {
			if (v->kind == 's')
				snprintf(hex + 2 * i, 3, "%02x", (unsigned char)
					 ((const struct iec_string *)v->addr)->data[i]);
			else
				snprintf(hex + 4 * i, 5, "%04x", (unsigned int)
					 ((const struct iec_wstring *)v->addr)->data[i]);
		}
		hex[(size_t)len * digits] = 0;
		if (!force && seen[idx] && last_s[idx] && strcmp(hex, last_s[idx]) == 0) {
			free(hex);
			return;
		}
		free(last_s[idx]);
		last_s[idx] = hex;
		printf("v %lld %d %c%s\n", t, idx, v->kind, hex);
	} else {
		long long x = get_int(v);

		if (!force && seen[idx] && x == last_int[idx])
			return;
		last_int[idx] = x;
		if (v->kind == 'u' && v->size == 8)
			printf("v %lld %d %" PRIu64 "\n", t, idx, (uint64_t)x);
		else
			printf("v %lld %d %lld\n", t, idx, x);
	}
	seen[idx] = 1;
}

static const char *pou_file(const char *pou)
{
	int i;

	for (i = 0; pou && i < sim_npou_files; i++)
		if (strcmp(sim_pou_files[i].pou, pou) == 0)
			return sim_pou_files[i].path;
	return "?";
}

int main(int argc, char **argv)
{
	long long end, t = 0;
	int *watch, nwatch = argc - 3;
	long long *next_release, *cycles, *late;
	iec_bool *prev_single;
	unsigned char *faulted, *pending;
	struct iec_ctx *ctx;
	const char *unbound;
	int i;

	if (argc < 3)
		die("usage: sim END_NS EVENTS_FILE WATCH_INDEX...");
	end = strtoll(argv[1], NULL, 10);
	load_events(argv[2]);
	watch = calloc((size_t)nwatch + 1, sizeof(*watch));
	for (i = 0; i < nwatch; i++) {
		watch[i] = atoi(argv[3 + i]);
		if (watch[i] < 0 || watch[i] >= sim_nvars)
			die("watch index out of range");
	}
	last_int = calloc((size_t)sim_nvars + 1, sizeof(*last_int));
	last_f = calloc((size_t)sim_nvars + 1, sizeof(*last_f));
	last_s = calloc((size_t)sim_nvars + 1, sizeof(*last_s));
	seen = calloc((size_t)sim_nvars + 1, 1);
	next_release = calloc((size_t)sim_ntasks + 1, sizeof(*next_release));
	cycles = calloc((size_t)sim_ntasks + 1, sizeof(*cycles));
	late = calloc((size_t)sim_ntasks + 1, sizeof(*late));
	prev_single = calloc((size_t)sim_ntasks + 1, sizeof(*prev_single));
	faulted = calloc((size_t)sim_ntasks + 1, 1);
	pending = calloc((size_t)sim_ntasks + 1, 1);
	ctx = calloc((size_t)sim_ntasks + 1, sizeof(*ctx));
	if (!watch || !last_int || !last_f || !last_s || !seen || !next_release ||
	    !cycles || !late || !prev_single || !faulted || !pending || !ctx)
		die("out of memory");

	sim_init();
	unbound = sim_unbound_pointer();
	if (unbound) {
		fprintf(stderr, "sim: pointer member %s is not bound after initialisation\n",
			unbound);
		exit(70);
	}
	for (i = 0; i < sim_ntasks; i++) {
		iec_ctx_init(&ctx[i], sim_tasks[i].loop_budget);
		if (sim_tasks[i].single)
			prev_single[i] = *sim_tasks[i].single;
	}
	for (;;) {
		int ran;

		while (next_event < nevents && events[next_event].t <= t)
			apply(&events[next_event++]);
		for (i = 0; i < sim_ntasks; i++)
			if (sim_tasks[i].interval_ns && next_release[i] == t)
				pending[i] = 1;
		do {
			const struct sim_task *tk;
			unsigned int granted;
			int best = -1;

			/* rising edges of SINGLE variables release event tasks */
			for (i = 0; i < sim_ntasks; i++) {
				const iec_bool *s = sim_tasks[i].single;

				if (!s)
					continue;
				if (*s && !prev_single[i])
					pending[i] = 1;
				prev_single[i] = *s;
			}
			for (i = 0; i < sim_ntasks; i++)
				if (pending[i] && (best < 0 || sim_tasks[i].priority <
						   sim_tasks[best].priority))
					best = i;
			ran = best >= 0;
			if (!ran)
				break;
			pending[best] = 0;
			if (faulted[best])
				continue;
			tk = &sim_tasks[best];
			iec_ctx_cycle_begin(&ctx[best], t);
			if (tk->watchdog_ns &&
			    tk->watchdog_ns / SIM_ITERATION_NS < ctx[best].loop_budget) {
				ctx[best].loop_budget =
					(unsigned int)(tk->watchdog_ns / SIM_ITERATION_NS);
				ctx[best].budget_fault = IEC_FAULT_WATCHDOG;
			}
			granted = ctx[best].loop_budget;
			ctx[best].sel_epoch = sim_sel_epoch;
			sim_globals_save();
			tk->run(&ctx[best]);
			cycles[best]++;
			if (ctx[best].fault == IEC_FAULT_NONE && tk->interval_ns &&
			    tk->watchdog_overruns) {
				long long used = (long long)(granted - ctx[best].loop_budget);

				if (used * SIM_ITERATION_NS > tk->interval_ns) {
					if (++late[best] >= tk->watchdog_overruns)
						iec_fault_raise(&ctx[best], IEC_FAULT_OVERRUN);
				} else {
					late[best] = 0;
				}
			}
			if (ctx[best].fault != IEC_FAULT_NONE) {
				/* as in the kernel: a faulting cycle writes no global */
				sim_globals_restore();
				faulted[best] = 1;
				printf("f %lld %s %s|%s|%s|%d\n", t, sim_tasks[best].name,
				       iec_fault_name(ctx[best].fault),
				       ctx[best].fault_pou ? ctx[best].fault_pou : "?",
				       pou_file(ctx[best].fault_pou),
				       ctx[best].fault_line);
			}
		} while (ran);
		for (i = 0; i < nwatch; i++)
			print_value(t, watch[i], 0);
		for (i = 0; i < sim_ntasks; i++)
			if (sim_tasks[i].interval_ns && next_release[i] == t)
				next_release[i] += sim_tasks[i].interval_ns;
		{
			long long nt = end + 1;

			for (i = 0; i < sim_ntasks; i++)
				if (sim_tasks[i].interval_ns && next_release[i] < nt)
					nt = next_release[i];
			if (next_event < nevents && events[next_event].t < nt)
				nt = events[next_event].t;
			if (nt > end)
				break;
			t = nt;
		}
	}
	for (i = 0; i < sim_ntasks; i++)
		printf("n %s %lld\n", sim_tasks[i].name, cycles[i]);
	for (i = 0; i < sim_ntasks; i++)
		if (ctx[i].sel_evaluated || ctx[i].sel_plain || ctx[i].sel_skipped)
			printf("s %s %llu %llu\n", sim_tasks[i].name,
			       (unsigned long long)(ctx[i].sel_evaluated +
						    ctx[i].sel_plain),
			       (unsigned long long)ctx[i].sel_skipped);
	for (i = 0; i < nevents; i++)
		free(events[i].s);
	for (i = 0; i < sim_nvars; i++)
		free(last_s[i]);
	free(events);
	free(watch);
	free(last_int);
	free(last_f);
	free(last_s);
	free(seen);
	free(next_release);
	free(cycles);
	free(prev_single);
	free(faulted);
	free(late);
	free(pending);
	free(ctx);
	return 0;
}
