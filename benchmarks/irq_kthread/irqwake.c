// SPDX-License-Identifier: GPL-2.0-only OR MIT
/*
 * irqwake.c - the reference of benchmarks/irq_latency.py: a plain kernel
 * thread woken by the parallel port's ACK interrupt the way iec2kmod wakes
 * an interrupt-bound event task (kmod_templates/kernel/iec_io.c and
 * iec_io_comedi.c): the same primary handler (hard interrupt context,
 * IRQF_ONESHOT: the interrupt enable checked, the status register read,
 * the time stamped), a threaded handler that marks the event pending and
 * wakes the thread, and the thread at SCHED_FIFO 49 (the FIFO priority of
 * an IEC task of PRIORITY 0).  The thread measures stamp -> its own first
 * instruction after the wake-up; the module logs the distribution at
 * unload, in iec2kmod's histogram buckets (iec_hist_bucket()).
 *
 * The port is comedi_parport's (attached with its I/O base only): this
 * module only reads its registers and sets and clears the control
 * register's interrupt enable, which comedi_parport's writes keep.  A
 * benchmark tool, not a driver: it does not take comedi's device mutex.
 *
 *   insmod irqwake.ko [irq=7] [io=0x378]
 */
#include <linux/interrupt.h>
#include <linux/io.h>
#include <linux/kthread.h>
#include <linux/module.h>
#include <linux/sched.h>
#include <linux/sched/types.h>
#include <linux/timekeeping.h>
#include <uapi/linux/sched/types.h>

#define IRQWAKE_STATUS	1
#define IRQWAKE_CTRL	2
#define IRQWAKE_IRQ_ENA	0x10
#define IRQWAKE_BUCKETS	64

static unsigned int irq = 7;
module_param(irq, uint, 0444);
MODULE_PARM_DESC(irq, "the parallel port's interrupt line (7)");
static unsigned int io = 0x378;
module_param(io, uint, 0444);
MODULE_PARM_DESC(io, "the parallel port's I/O base (0x378)");

static struct task_struct *irqwake_thread;
static ktime_t irqwake_stamp;		/* primary handler */
static ktime_t irqwake_event;		/* threaded handler -> thread */
static bool irqwake_pending;
static u64 irqwake_irqs;		/* threaded handler */
static u64 irqwake_n, irqwake_hist[IRQWAKE_BUCKETS];	/* thread */
static s64 irqwake_min = S64_MAX, irqwake_max, irqwake_sum;

/* iec2kmod's log-linear buckets (iec_kmod.h, iec_hist_bucket()) */
static u32 irqwake_bucket(s64 ns)
{
	u64 us = ns > 0 ? (u64)ns / NSEC_PER_USEC : 0;
	u32 o, b;

	if (us < 32)
		return us;
	o = ilog2(us) - 5;
	b = 32 + 4 * o + ((us >> (o + 3)) & 3);
	return min_t(u32, b, IRQWAKE_BUCKETS - 1);
}

static irqreturn_t irqwake_hardirq(int line, void *arg)
{
	if (!(inb(io + IRQWAKE_CTRL) & IRQWAKE_IRQ_ENA))
		return IRQ_NONE;
	inb(io + IRQWAKE_STATUS);
	WRITE_ONCE(irqwake_stamp, ktime_get());
	return IRQ_WAKE_THREAD;
}

static irqreturn_t irqwake_threadfn(int line, void *arg)
{
	irqwake_irqs++;
	WRITE_ONCE(irqwake_event, READ_ONCE(irqwake_stamp));
	smp_wmb();	/* the stamp before the event */
	WRITE_ONCE(irqwake_pending, true);
	wake_up_process(irqwake_thread);
	return IRQ_HANDLED;
}

static int irqwake_fn(void *arg)
{
	for (;;) {
		ktime_t stamp;
		s64 lat;

		set_current_state(TASK_INTERRUPTIBLE);
		if (kthread_should_stop())
			break;
		if (!READ_ONCE(irqwake_pending)) {
			schedule();
			continue;
		}
		__set_current_state(TASK_RUNNING);
		WRITE_ONCE(irqwake_pending, false);
		smp_mb();	/* pairs with irqwake_threadfn() */
		stamp = READ_ONCE(irqwake_event);
		lat = ktime_to_ns(ktime_sub(ktime_get(), stamp));
		irqwake_n++;
		irqwake_hist[irqwake_bucket(lat)]++;
		irqwake_min = min(irqwake_min, lat);
		irqwake_max = max(irqwake_max, lat);
		irqwake_sum += lat;
	}
	__set_current_state(TASK_RUNNING);
	return 0;
}

static void irqwake_enable(bool on)
{
	u8 ctrl = inb(io + IRQWAKE_CTRL);

	inb(io + IRQWAKE_STATUS);
	outb(on ? ctrl | IRQWAKE_IRQ_ENA : ctrl & ~IRQWAKE_IRQ_ENA, io + IRQWAKE_CTRL);
	inb(io + IRQWAKE_STATUS);
}

static int __init irqwake_init(void)
{
	struct sched_attr attr = {
		.size = sizeof(attr),
		.sched_policy = SCHED_FIFO,
		.sched_priority = 49,
	};
	int ret;

	irqwake_thread = kthread_create(irqwake_fn, NULL, "irqwake");
	if (IS_ERR(irqwake_thread))
		return PTR_ERR(irqwake_thread);
	ret = sched_setattr_nocheck(irqwake_thread, &attr);
	if (ret)
		goto err_thread;
	wake_up_process(irqwake_thread);
	ret = request_threaded_irq(irq, irqwake_hardirq, irqwake_threadfn,
				   IRQF_ONESHOT, "irqwake", &irqwake_n);
	if (ret)
		goto err_thread;
	irqwake_enable(true);
	return 0;

err_thread:
	kthread_stop(irqwake_thread);
	return ret;
}

static void __exit irqwake_exit(void)
{
	char line[IRQWAKE_BUCKETS * 8];
	int len = 0;
	u32 b;

	irqwake_enable(false);
	free_irq(irq, &irqwake_n);	/* no handler runs after it */
	kthread_stop(irqwake_thread);
	for (b = 0; b < IRQWAKE_BUCKETS; b++)
		len += scnprintf(line + len, sizeof(line) - len, " %llu", irqwake_hist[b]);
	pr_info("irqwake: irqs %llu wakes %llu min_ns %lld max_ns %lld sum_ns %lld hist%s\n",
		irqwake_irqs, irqwake_n, irqwake_n ? irqwake_min : 0, irqwake_max,
		irqwake_sum, line);
}

module_init(irqwake_init);
module_exit(irqwake_exit);
MODULE_LICENSE("Dual MIT/GPL");
MODULE_DESCRIPTION("iec2kmod benchmark: a kernel thread woken by the parallel port's ACK interrupt");
