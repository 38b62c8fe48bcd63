// SPDX-License-Identifier: GPL-2.0-only OR MIT
/*
 * iec_resource_rt.c - the task loop of a resource module.  Included by the
 * generated resource module (its functions are static: every resource
 * module has its own copy).
 *
 * One kthread per TASK, created stopped.  A periodic task sleeps until an
 * absolute deadline (hrtimer, hard mode: the timerlat pattern); a deadline
 * already in the past when the cycle ends is an overrun: the missed
 * releases are skipped and counted.  An event task sleeps until its SINGLE
 * variable rises (iec2kmod_event()) or its interrupt comes (iec_io.c).  Each cycle: copy the globals in under
 * the image lock, run the programs, copy the written globals out, account.
 * IEC priority 0..48 maps to SCHED_FIFO 49..1: below the threaded
 * interrupt handlers (50), as on OpenPLC and LinuxCNC.
 *
 * The watchdog: a hard hrtimer armed for watchdog_ns at the start of each
 * cycle empties the cycle's loop budget when it fires, with the fault
 * IEC_FAULT_WATCHDOG; the next loop iteration of the body faults there,
 * located at its POU and line (iec_loop_tick()).  It fires again every
 * IEC_WATCHDOG_AGAIN_NS until the cycle ends (the body may have written
 * the budget back between reading and storing it).  A cycle that ends after
 * the time ran out without passing a loop iteration faults at its end.
 * watchdog_overruns cycles in a row that end after the next release fault
 * the task (IEC_FAULT_OVERRUN) before the last one's results are copied
 * out.
 *
 * Unloading: while a task is active (started, until it acknowledges a
 * stop or a fault by going idle) its thread holds a reference on this
 * module, so rmmod refuses ("in use") instead of waiting in module exit
 * for a cycle that may never end; exit runs only with every thread idle
 * and kthread_stop() returns at once.
 */
#include <linux/cpumask.h>
#include <linux/delay.h>
#include <linux/hrtimer.h>
#include <linux/kthread.h>
#include <linux/sched.h>
#include <linux/sched/types.h>
#include <linux/sysfs.h>
#include <linux/string.h>
#include <linux/timekeeping.h>
#include <uapi/linux/sched/types.h>

#include "iec_kmod.h"

#define IEC_FIFO_TOP	49
#define IEC_WATCHDOG_AGAIN_NS	(100 * NSEC_PER_USEC)

static struct iec_resource *iec_this_res;

/*
 * /sys/module/<resource module>/iec_latency: per task, the release latency
 * histogram (IEC_HIST_BUCKETS: log-linear, the last bucket counts the
 * overflow), for the jitter benchmark.  Root-only.
 */
static ssize_t iec_latency_show(struct kobject *kobj, struct kobj_attribute *attr,
				char *buf)
{
	struct iec_resource *res = iec_this_res;
	int len = 0;
	u32 i, b;

	for (i = 0; res && i < res->ntasks; i++) {
		const struct iec_task_stats *s = &res->tasks[i].stats;

		/* a line is at most ~1500 bytes: stop while the page has room */
		if (len > PAGE_SIZE - 1600) {
			len += sysfs_emit_at(buf, len, "...\n");
			break;
		}
		len += sysfs_emit_at(buf, len, "%s cycles %llu overruns %llu max_ns %lld sum_ns %lld hist",
				     res->tasks[i].name, s->cycles, s->overruns,
				     s->latency_max_ns, s->latency_sum_ns);
		for (b = 0; b < IEC_HIST_BUCKETS; b++)
			len += sysfs_emit_at(buf, len, " %llu", s->hist[b]);
		len += sysfs_emit_at(buf, len, "\n");
	}
	return len;
}

static struct kobj_attribute iec_latency_attr = __ATTR(iec_latency, 0400,
						       iec_latency_show, NULL);

static void iec_task_account(struct iec_task *t, s64 latency, s64 exec)
{
	struct iec_task_stats *s = &t->stats;

	s->cycles++;
	if (latency < 0)
		latency = 0;
	s->hist[iec_hist_bucket(latency)]++;
	if (latency > s->latency_max_ns)
		s->latency_max_ns = latency;
	s->latency_sum_ns += latency;
	if (s->cycles == 1 || exec < s->exec_min_ns)
		s->exec_min_ns = exec;
	if (exec > s->exec_max_ns)
		s->exec_max_ns = exec;
	s->exec_sum_ns += exec;
}

/* Hard interrupt context: the cycle's time is up. */
static enum hrtimer_restart iec_watchdog_fire(struct hrtimer *timer)
{
	struct iec_task *t = container_of(timer, struct iec_task, watchdog);

	WRITE_ONCE(t->ctx.budget_fault, IEC_FAULT_WATCHDOG);
	smp_wmb();	/* the fault before the empty budget (iec_loop_tick) */
	WRITE_ONCE(t->ctx.loop_budget, 0);
	hrtimer_forward_now(timer, ns_to_ktime(IEC_WATCHDOG_AGAIN_NS));
	return HRTIMER_RESTART;
}

/* After the programs ran: the watchdog's faults that no loop noticed. */
static void iec_watchdog_check(struct iec_task *t, ktime_t release)
{
	if (t->watchdog_ns) {
		hrtimer_cancel(&t->watchdog);
		if (t->ctx.fault == IEC_FAULT_NONE &&
		    READ_ONCE(t->ctx.budget_fault) == IEC_FAULT_WATCHDOG)
			iec_fault_raise(&t->ctx, IEC_FAULT_WATCHDOG);
	}
	if (!t->interval_ns || !t->watchdog_overruns ||
	    t->ctx.fault != IEC_FAULT_NONE)
		return;
	if (ktime_after(ktime_get(), ktime_add_ns(release, t->interval_ns))) {
		if (++t->late >= t->watchdog_overruns)
			iec_fault_raise(&t->ctx, IEC_FAULT_OVERRUN);
	} else {
		t->late = 0;
	}
}

/* The task stops on the fault its ctx holds; the status names it. */
static void iec_task_fault(struct iec_task *t)
{
	t->stats.faults++;
	t->stats.fault_code = t->ctx.fault;
	t->stats.fault_pou = t->ctx.fault_pou;
	/* the POU name lives in a program module, which may go */
	strscpy(t->stats.fault_pou_name,
		t->ctx.fault_pou ? t->ctx.fault_pou : "?",
		sizeof(t->stats.fault_pou_name));
	t->stats.fault_line = t->ctx.fault_line;
	t->stats.fault_time = ktime_get_real();
	smp_store_release(&t->state, IEC_TASK_FAULT);
	pr_warn("iec2kmod: task %s.%s stopped: %s in %s line %d\n",
		t->res->name, t->name, iec_fault_name(t->ctx.fault),
		t->ctx.fault_pou ? t->ctx.fault_pou : "?",
		t->ctx.fault_line);
}

/*
 * One cycle.  The programs' clock (timers) reads the cycle's release time,
 * not the moment the thread got the CPU: time advances by exactly one
 * interval per cycle, as in `iec2kmod sim`, whatever the wake-up latency.
 */
static void iec_task_cycle(struct iec_task *t, ktime_t release)
{
	ktime_t start = ktime_get();

	iec_ctx_cycle_begin(&t->ctx, ktime_to_ns(release));
	/* RTC's clock: the wall clock at the release, not at the wake-up */
	t->ctx.wall_ns = ktime_to_ns(ktime_mono_to_real(release));
	if (t->watchdog_ns)
		hrtimer_start(&t->watchdog, ns_to_ktime(t->watchdog_ns),
			      HRTIMER_MODE_REL_HARD);
	iec2kmod_cycle_begin(t);	/* forces; the manager waits from here */
	t->copy_in(t);
	if (t->ctx.fault == IEC_FAULT_NONE)	/* an input device failed */
		t->run(&t->ctx);
	iec_watchdog_check(t, release);
	if (t->ctx.fault != IEC_FAULT_NONE) {
		/* the task stops; its results of this cycle are not written */
		iec_task_fault(t);
	} else {
		t->copy_out(t);
		if (t->ctx.fault != IEC_FAULT_NONE)	/* an output device failed */
			iec_task_fault(t);
	}
	iec2kmod_cycle_end(t);
	/* when the cycle's values were published (plc-manager serve stamps them) */
	WRITE_ONCE(t->stats.last_end, ktime_get_real());
	iec_task_account(t, ktime_to_ns(ktime_sub(start, release)),
			 ktime_to_ns(ktime_sub(ktime_get(), start)));
}

/* Sleeps until the absolute monotonic deadline; false if told to stop. */
static bool iec_sleep_until(struct iec_task *t, ktime_t deadline)
{
	while (!kthread_should_stop() &&
	       smp_load_acquire(&t->state) == IEC_TASK_RUNNING) {
		ktime_t d = deadline;

		set_current_state(TASK_INTERRUPTIBLE);
		if (schedule_hrtimeout_range(&d, 0, HRTIMER_MODE_ABS_HARD) == 0)
			return true;
	}
	__set_current_state(TASK_RUNNING);
	return false;
}

/*
 * Waits for an event; false if told to stop.  *release is the event's:
 * an interrupt's time (iec_io.c), or now for a SINGLE variable's edge.
 */
static bool iec_wait_event(struct iec_task *t, ktime_t *release)
{
	for (;;) {
		set_current_state(TASK_INTERRUPTIBLE);
		if (kthread_should_stop() ||
		    smp_load_acquire(&t->state) != IEC_TASK_RUNNING) {
			__set_current_state(TASK_RUNNING);
			return false;
		}
		if (READ_ONCE(t->event_pending)) {
			__set_current_state(TASK_RUNNING);
			WRITE_ONCE(t->event_pending, false);
			/* a full barrier: pairs with iec_io_irq_thread() */
			*release = xchg(&t->event_time, 0);
			if (!*release)
				*release = ktime_get();
			return true;
		}
		schedule();
	}
}

static void iec_wait_stop(void)
{
	for (;;) {
		set_current_state(TASK_INTERRUPTIBLE);
		if (kthread_should_stop())
			break;
		schedule();
	}
	__set_current_state(TASK_RUNNING);
}

/*
 * The thread acknowledges a stop or a fault: no cycle runs until a start.
 * The reference goes first, so a stop that saw the acknowledgement can
 * remove the module at once; until this thread returns, module exit waits
 * for it in kthread_stop().
 */
static void iec_task_idle(struct iec_task *t)
{
	if (t->io_safe)
		t->io_safe(t);	/* its bound outputs: safe state (iec_io.c) */
	module_put(THIS_MODULE);
	iec2kmod_task_idle(t);
}

/*
 * Waits for a start; false if told to stop.  Returns true active, with a
 * reference on this module (none is given while the module is going).
 */
static bool iec_wait_started(struct iec_task *t)
{
	for (;;) {
		set_current_state(TASK_INTERRUPTIBLE);
		if (kthread_should_stop())
			break;
		if (smp_load_acquire(&t->state) != IEC_TASK_RUNNING) {
			schedule();
			continue;
		}
		__set_current_state(TASK_RUNNING);
		if (!try_module_get(THIS_MODULE)) {
			iec_wait_stop();	/* rmmod is under way */
			return false;
		}
		WRITE_ONCE(t->active, true);
		smp_mb();	/* pairs with iec_wait_resource_idle() */
		if (smp_load_acquire(&t->state) == IEC_TASK_RUNNING)
			return true;
		iec_task_idle(t);	/* stopped meanwhile */
	}
	__set_current_state(TASK_RUNNING);
	return false;
}

static int iec_task_thread(void *arg)
{
	struct iec_task *t = arg;

	while (iec_wait_started(t)) {
		if (!t->interval_ns) {
			ktime_t release;

			while (iec_wait_event(t, &release))
				iec_task_cycle(t, release);
			iec_task_idle(t);
			continue;
		}
		t->next = t->first;	/* the common first release */
		if (!iec_sleep_until(t, t->next)) {
			iec_task_idle(t);	/* stopped before it */
			continue;
		}
		for (;;) {
			s64 late;

			iec_task_cycle(t, t->next);
			if (smp_load_acquire(&t->state) != IEC_TASK_RUNNING)
				break;
			t->next = ktime_add_ns(t->next, t->interval_ns);
			late = ktime_to_ns(ktime_sub(ktime_get(), t->next));
			if (late > 0 && t->until) {
				/*
				 * a run of a fixed length runs every release
				 * before its end, late ones late, so that the
				 * number of cycles is exact
				 */
				t->stats.overruns++;
			} else if (late > 0) {
				/* skip the releases that already passed */
				u64 missed = div64_u64((u64)late, t->interval_ns) + 1;

				t->stats.overruns += missed;
				t->next = ktime_add_ns(t->next, missed * t->interval_ns);
			}
			if (t->until && !ktime_before(t->next, t->until)) {
				/* a run of a fixed length ("run" command) is over */
				smp_store_release(&t->state, IEC_TASK_STOPPED);
				break;
			}
			if (!iec_sleep_until(t, t->next))
				break;
		}
		iec_task_idle(t);
	}
	return 0;
}

static int iec_task_create(struct iec_resource *res, struct iec_task *t)
{
	struct sched_attr attr = {
		.size = sizeof(attr),
		.sched_policy = SCHED_FIFO,
		.sched_priority = IEC_FIFO_TOP - t->priority,
	};
	struct task_struct *p;
	int ret;

	t->res = res;
	raw_spin_lock_init(&t->var_lock);
	hrtimer_init(&t->watchdog, CLOCK_MONOTONIC, HRTIMER_MODE_REL_HARD);
	t->watchdog.function = iec_watchdog_fire;
	iec_ctx_init(&t->ctx, t->loop_budget);
	t->ctx.task_id = t->task_id;
	p = kthread_create(iec_task_thread, t, "iec/%s/%s", res->name, t->name);
	if (IS_ERR(p))
		return PTR_ERR(p);
	if (res->cpu >= 0) {
		if (!cpu_online(res->cpu)) {
			kthread_stop(p);
			pr_err("iec2kmod: resource %s: CPU %d is not online\n",
			       res->name, res->cpu);
			return -ENODEV;
		}
		kthread_bind(p, res->cpu);
	}
	ret = sched_setattr_nocheck(p, &attr);
	if (ret) {
		kthread_stop(p);
		return ret;
	}
	t->thread = p;
	wake_up_process(p);	/* it waits for start */
	return 0;
}

/* Starts a task that is stopped or stopped on a fault; its fault stays
 * recorded (the last fault), its program instances keep their state. */
static int iec_resource_start_task(struct iec_resource *res, u32 i)
{
	struct iec_task *t;

	if (i >= res->ntasks)
		return -EINVAL;
	t = &res->tasks[i];
	if (smp_load_acquire(&t->state) == IEC_TASK_RUNNING)
		return 0;
	iec_fault_clear(&t->ctx);
	t->late = 0;
	t->stats.starts++;
	t->stats.started = ktime_get_real();
	WRITE_ONCE(t->event_pending, false);
	t->first = res->epoch;
	t->until = res->until;
	smp_store_release(&t->state, IEC_TASK_RUNNING);
	wake_up_process(t->thread);
	return 0;
}

static int iec_resource_start(struct iec_resource *res)
{
	u32 i;

	for (i = 0; i < res->ntasks; i++)
		iec_resource_start_task(res, i);
	return 0;
}

static void iec_resource_stop(struct iec_resource *res)
{
	u32 i;

	for (i = 0; i < res->ntasks; i++) {
		struct iec_task *t = &res->tasks[i];

		if (smp_load_acquire(&t->state) == IEC_TASK_RUNNING)
			smp_store_release(&t->state, IEC_TASK_STOPPED);
		wake_up_process(t->thread);
	}
}

static void iec_resource_destroy(struct iec_resource *res)
{
	u32 i;

	for (i = 0; i < res->ntasks; i++) {
		struct iec_task *t = &res->tasks[i];

		if (!t->thread)
			continue;
		smp_store_release(&t->state, IEC_TASK_STOPPED);
		kthread_stop(t->thread);	/* waits for the cycle to end */
		t->thread = NULL;
		hrtimer_cancel(&t->watchdog);
	}
}

static int iec_resource_init(struct iec_resource *res)
{
	u32 i;
	int ret;

	res->start = iec_resource_start;
	res->start_task = iec_resource_start_task;
	res->stop = iec_resource_stop;
	for (i = 0; i < res->ntasks; i++) {
		ret = iec_task_create(res, &res->tasks[i]);
		if (ret)
			goto err_threads;
	}
	ret = iec2kmod_register_resource(res);
	if (ret)
		goto err_threads;
	iec_this_res = res;
	if (sysfs_create_file(&THIS_MODULE->mkobj.kobj, &iec_latency_attr.attr))
		pr_warn("iec2kmod: resource %s: no iec_latency file in sysfs\n", res->name);
	return 0;

err_threads:
	iec_resource_destroy(res);
	return ret;
}

static void iec_resource_exit(struct iec_resource *res)
{
	sysfs_remove_file(&THIS_MODULE->mkobj.kobj, &iec_latency_attr.attr);
	iec2kmod_unregister_resource(res);
	iec_resource_destroy(res);
	iec2kmod_resource_gone(res);	/* forces pointing into this module */
}
