/* SPDX-License-Identifier: GPL-2.0-only OR MIT */
/*
 * iec_fault.h - per-task runtime context and defined runtime faults.
 *
 * Every POU body receives the task's struct iec_ctx.  It carries the time
 * the task cycle started (timers read it, so one cycle sees one time), the
 * loop budget of the cycle, and the first runtime fault of the cycle.
 *
 * Fault protocol (what the code generator must emit):
 *
 *  1. Operations that can fail are done by helpers that take the ctx:
 *     iec_div_<t>, iec_mod_<t>, iec_index, iec_range_<t>, iec_enum_check,
 *     iec_mux_index, iec_loop_tick, iec_div_time ...  On failure a helper
 *     records the fault (iec_fault_raise) and returns a defined value
 *     (0, a safe index, the subrange's low bound) so the rest of the
 *     expression is still well defined.
 *  2. After each statement that contains such a helper or a call to another
 *     POU, the generated code does
 *             IEC_FAULT_CHECK(ctx, "POU_NAME", line);
 *     which, if a fault is pending, records where (only the innermost POU,
 *     the first to locate it, is kept) and returns from the body.  A
 *     function returns its (defined) result variable; use
 *     IEC_FAULT_CHECK_RET(ctx, pou, line, retval) there.  A scalar
 *     assignment that can fault computes its value, its place and its
 *     subrange check first and is checked before the store, so a
 *     faulting statement stores nothing (the defined values above never
 *     reach a variable).
 *  3. Loops: every iteration of WHILE, REPEAT and FOR starts with
 *             if (!iec_loop_tick(ctx)) { IEC_FAULT_LOCATE...; return; }
 *     (IEC_LOOP_TICK(ctx, pou, line) does exactly this.)  The budget is
 *     set by iec_ctx_cycle_begin() and counts iterations over the whole
 *     cycle, so a loop that never ends records IEC_FAULT_LOOP and the task
 *     regains control.
 *  4. The task loop calls iec_ctx_cycle_begin() before the programs of a
 *     cycle, reads ctx->fault after them, accounts it, and decides (stop or
 *     go on); iec_fault_clear() resets the fault state.  A fault left set
 *     makes every later body return at its first check.
 *
 * Only the first fault of a cycle is kept in code/pou/line; fault_count
 * counts every raise.
 */
#ifndef IEC_FAULT_H
#define IEC_FAULT_H

#include "iec_types.h"

enum iec_fault_code {
	IEC_FAULT_NONE = 0,
	IEC_FAULT_DIV_ZERO,	/* integer or TIME division / MOD by zero */
	IEC_FAULT_INDEX,	/* array index out of its declared range */
	IEC_FAULT_RANGE,	/* value outside a subrange type */
	IEC_FAULT_ENUM,		/* value that is not one of the enum's */
	IEC_FAULT_LOOP,		/* loop budget of the cycle exhausted */
	IEC_FAULT_MUX,		/* MUX selector K out of range */
	IEC_FAULT_USER,		/* raised by the program itself */
	IEC_FAULT_WATCHDOG,	/* the cycle ran longer than its watchdog time */
	IEC_FAULT_OVERRUN,	/* too many cycles in a row ended late */
	IEC_FAULT_FRAME,	/* frame area too small (never, by construction) */
	IEC_FAULT_IO,		/* a bound I/O device failed (iec_io.c) */
	IEC_FAULT__COUNT
};

/*
 * Default iteration budget per cycle when the task sets none: the one every
 * generated task sets (iec2kmod/execmodel.py LOOP_BUDGET, checked by
 * tests/unit/test_compilation.py).
 */
#define IEC_LOOP_BUDGET_DEFAULT	1000000U

struct iec_ctx {
	iec_s64 now_ns;			/* time the task cycle started */
	/*
	 * the date and time (DT, ns since 1970-01-01) the cycle started, read
	 * by RTC: the kernel sets it to the wall clock at the cycle's release
	 * after iec_ctx_cycle_begin(); elsewhere (the simulator) it is now_ns
	 * from the epoch DT#1970-01-01-00:00:00, so runs are deterministic
	 */
	iec_s64 wall_ns;
	iec_u32 loop_budget;		/* iterations left in this cycle */
	iec_u32 loop_budget_cycle;	/* budget granted at cycle start */
	/*
	 * the fault an exhausted budget raises: IEC_FAULT_LOOP, or
	 * IEC_FAULT_WATCHDOG when the watchdog ended the cycle (the kernel's
	 * watchdog timer empties the budget; the simulation grants only the
	 * iterations that fit in the watchdog time)
	 */
	enum iec_fault_code budget_fault;
	enum iec_fault_code fault;	/* first fault, IEC_FAULT_NONE if none */
	const char *fault_pou;		/* POU that raised it (NULL: unknown) */
	int fault_line;			/* source line in that POU, 0: unknown */
	iec_u32 fault_count;		/* faults raised since the last clear */
	/* selective execution (iec_sel.h, iec2kmod --selective) */
	iec_u32 sel_epoch;		/* bumped by writes into instances */
	bool sel_changed;		/* a nested evaluation changed its state */
	iec_u64 sel_evaluated;		/* blocks evaluated, but: */
	iec_u64 sel_plain;		/* blocks evaluated plainly while busy */
	iec_u64 sel_skipped;		/* blocks skipped */
	iec_u64 sel_cycle;		/* cycles begun: busy periods end by it */
	/* frame area of the running program's module, see iec_frame_push() */
	iec_u8 *frame_base;
	iec_u32 frame_size;
	iec_u32 frame_used;
	iec_u32 task_id;		/* the task's index in its configuration */
};

static inline void iec_ctx_init(struct iec_ctx *ctx, iec_u32 loop_budget)
{
	iec_memset(ctx, 0, sizeof(*ctx));
	ctx->loop_budget_cycle = loop_budget ? loop_budget :
					       IEC_LOOP_BUDGET_DEFAULT;
	ctx->loop_budget = ctx->loop_budget_cycle;
	ctx->budget_fault = IEC_FAULT_LOOP;
}

static inline void iec_ctx_cycle_begin(struct iec_ctx *ctx, iec_s64 now_ns)
{
	ctx->now_ns = now_ns;
	ctx->wall_ns = now_ns;
	ctx->sel_cycle++;
	ctx->loop_budget = ctx->loop_budget_cycle;
	ctx->budget_fault = IEC_FAULT_LOOP;
}

static inline void iec_fault_clear(struct iec_ctx *ctx)
{
	ctx->fault = IEC_FAULT_NONE;
	ctx->fault_pou = NULL;
	ctx->fault_line = 0;
	ctx->fault_count = 0;
}

static inline void iec_fault_raise(struct iec_ctx *ctx,
				   enum iec_fault_code code)
{
	if (ctx->fault == IEC_FAULT_NONE)
		ctx->fault = code;
	if (ctx->fault_count != IEC_U32_MAX)
		ctx->fault_count++;
}

/* Record where the pending fault was noticed; the first caller wins. */
static inline void iec_fault_locate(struct iec_ctx *ctx, const char *pou,
				    int line)
{
	if (!ctx->fault_pou) {
		ctx->fault_pou = pou;
		ctx->fault_line = line;
	}
}

static inline const char *iec_fault_name(enum iec_fault_code code)
{
	switch (code) {
	case IEC_FAULT_NONE:
		return "none";
	case IEC_FAULT_DIV_ZERO:
		return "division by zero";
	case IEC_FAULT_INDEX:
		return "array index out of range";
	case IEC_FAULT_RANGE:
		return "subrange value out of range";
	case IEC_FAULT_ENUM:
		return "invalid enumerated value";
	case IEC_FAULT_LOOP:
		return "endless loop (loop budget exhausted)";
	case IEC_FAULT_MUX:
		return "MUX selector out of range";
	case IEC_FAULT_USER:
		return "fault raised by the program";
	case IEC_FAULT_WATCHDOG:
		return "watchdog (cycle longer than the task's watchdog time)";
	case IEC_FAULT_OVERRUN:
		return "overruns (cycles in a row that ended after the next release)";
	case IEC_FAULT_FRAME:
		return "frame area exhausted";
	case IEC_FAULT_IO:
		return "I/O device error";
	default:
		return "unknown fault";
	}
}

/*
 * Frame area.  The strings, arrays, structures and FB instances a POU body
 * needs as temporaries or VAR_TEMP (function: VAR) do not live on the
 * kernel stack, whose frames must stay small: each POU that has any keeps
 * them in a struct <pou>_frame pushed on the task's frame area when it is
 * called and popped when it returns.  The code that owns the program's
 * code (a program-type module; the simulator) owns one area per task,
 * sized at compile time for the deepest chain of calls (IEC has no
 * recursion), and points ctx at it before the program body runs.  A push
 * that would not fit records IEC_FAULT_FRAME instead of overrunning.
 */
#define IEC_FRAME_ALIGN(n)	((((iec_u32)(n)) + 15U) & ~15U)
#define IEC_FRAME_MAX(a, b)	((iec_u32)(a) > (iec_u32)(b) ? (iec_u32)(a) : (iec_u32)(b))

static inline void iec_frame_area(struct iec_ctx *ctx, iec_u8 *base,
				  iec_u32 size)
{
	ctx->frame_base = base;
	ctx->frame_size = size;
	ctx->frame_used = 0;
}

static inline void *iec_frame_push(struct iec_ctx *ctx, iec_u32 size,
				   iec_u32 *mark)
{
	iec_u32 need = IEC_FRAME_ALIGN(size);
	void *p;

	*mark = ctx->frame_used;
	if (iec_unlikely(!ctx->frame_base || need > ctx->frame_size ||
			 ctx->frame_used > ctx->frame_size - need)) {
		iec_fault_raise(ctx, IEC_FAULT_FRAME);
		return NULL;
	}
	p = ctx->frame_base + ctx->frame_used;
	ctx->frame_used += need;
	return p;
}

static inline void iec_frame_pop(struct iec_ctx *ctx, iec_u32 mark)
{
	ctx->frame_used = mark;
}

#define IEC_FAULT_CHECK(ctx, pou, line)					\
	do {								\
		if (iec_unlikely((ctx)->fault != IEC_FAULT_NONE)) {	\
			iec_fault_locate((ctx), (pou), (line));		\
			return;						\
		}							\
	} while (0)

#define IEC_FAULT_CHECK_RET(ctx, pou, line, retval)			\
	do {								\
		if (iec_unlikely((ctx)->fault != IEC_FAULT_NONE)) {	\
			iec_fault_locate((ctx), (pou), (line));		\
			return (retval);				\
		}							\
	} while (0)

/*
 * Returns false (and records ctx->budget_fault: the endless loop, or the
 * watchdog) once the budget is used up.  The budget is read through a
 * volatile access: the kernel's watchdog timer empties it from interrupt
 * context, and a loop must see that at its next iteration.
 */
static inline bool iec_loop_tick(struct iec_ctx *ctx)
{
	iec_u32 left = *(volatile iec_u32 *)&ctx->loop_budget;

	if (iec_likely(left != 0)) {
		ctx->loop_budget = left - 1;
		return true;
	}
	iec_fault_raise(ctx, *(volatile enum iec_fault_code *)&ctx->budget_fault);
	return false;
}

#define IEC_LOOP_TICK(ctx, pou, line)					\
	do {								\
		if (iec_unlikely(!iec_loop_tick(ctx))) {		\
			iec_fault_locate((ctx), (pou), (line));		\
			return;						\
		}							\
	} while (0)

#define IEC_LOOP_TICK_RET(ctx, pou, line, retval)			\
	do {								\
		if (iec_unlikely(!iec_loop_tick(ctx))) {		\
			iec_fault_locate((ctx), (pou), (line));		\
			return (retval);				\
		}							\
	} while (0)

/*
 * Array index check.  ARRAY[lo..hi]: returns idx - lo, the zero-based C
 * index, when lo <= idx <= hi; otherwise records IEC_FAULT_INDEX and
 * returns 0, an index that is always valid.  Computed without overflow for
 * any 64-bit bounds.
 */
static inline iec_u64 iec_index(struct iec_ctx *ctx, iec_s64 idx, iec_s64 lo,
				 iec_s64 hi)
{
	if (iec_likely(idx >= lo && idx <= hi))
		return (iec_u64)idx - (iec_u64)lo;
	iec_fault_raise(ctx, IEC_FAULT_INDEX);
	return 0;
}

/*
 * MUX(K, IN0, ..., IN(n-1)): returns K when 0 <= K < n; otherwise records
 * IEC_FAULT_MUX and returns 0 (IN0 is selected).
 */
static inline iec_u32 iec_mux_index(struct iec_ctx *ctx, iec_s64 k,
				    iec_u32 n)
{
	if (iec_likely(k >= 0 && (iec_u64)k < n))
		return (iec_u32)k;
	iec_fault_raise(ctx, IEC_FAULT_MUX);
	return 0;
}

/*
 * Subrange check for a value about to be stored in a subrange variable:
 * returns v when lo <= v <= hi, else records IEC_FAULT_RANGE and returns
 * lo (a valid value of the type).  Signed values go through the _lint
 * variant, unsigned ones through _ulint.
 */
static inline iec_s64 iec_range_lint(struct iec_ctx *ctx, iec_s64 v,
				     iec_s64 lo, iec_s64 hi)
{
	if (iec_likely(v >= lo && v <= hi))
		return v;
	iec_fault_raise(ctx, IEC_FAULT_RANGE);
	return lo;
}

static inline iec_u64 iec_range_ulint(struct iec_ctx *ctx, iec_u64 v,
				      iec_u64 lo, iec_u64 hi)
{
	if (iec_likely(v >= lo && v <= hi))
		return v;
	iec_fault_raise(ctx, IEC_FAULT_RANGE);
	return lo;
}

/*
 * Enumerated value check for enums whose values are lo..hi (contiguous;
 * the compiler checks other sets with a switch and iec_fault_raise).
 * Returns v, or records IEC_FAULT_ENUM and returns dflt (the enum's
 * initial value).
 */
static inline iec_s64 iec_enum_check(struct iec_ctx *ctx, iec_s64 v,
				     iec_s64 lo, iec_s64 hi, iec_s64 dflt)
{
	if (iec_likely(v >= lo && v <= hi))
		return v;
	iec_fault_raise(ctx, IEC_FAULT_ENUM);
	return dflt;
}

#endif /* IEC_FAULT_H */
