// SPDX-License-Identifier: GPL-2.0-only OR MIT
/*
 * iec_io.c - bound I/O of a resource module: the provider interface and
 * the copy of device channels into and out of the process image.
 * Included by a generated resource module whose resource has an I/O map
 * (iec2kmod/iomap.py); its functions are static.
 *
 * Where the device access happens.  Copy-in and copy-out hold the image
 * lock, a raw spinlock: nothing may sleep there, while a provider may
 * (comedi takes the device's mutex).  So a task's cycle is:
 *
 *   1. iec_io_read():   every input the task reads, from its device, into
 *                       the task's staging array (its thread, preemptible,
 *                       no lock held);
 *   2. copy-in:         under the image lock, the staged inputs are stored
 *                       into their located variables (forced ones are
 *                       forced again), then the task's image is copied in;
 *   3. the programs run;
 *   4. copy-out:        under the image lock, the task's results go to the
 *                       image, the forces are applied, and the value of
 *                       each output the task writes is staged;
 *   5. iec_io_write():  the staged outputs to their devices (no lock held).
 *
 * Consistency: a task's programs see all its bound inputs sampled in one
 * burst just before the cycle's copy-in (not one instant: the samples are
 * taken one after the other, in the order of the I/O map), together with
 * the rest of the image as of that copy-in; its outputs reach the devices
 * right after the copy-out that produced them, with the forced value of a
 * forced output.  The image never holds a half-updated input: the store
 * happens under the same lock as the copy.  Each task stages into its own
 * array, so two tasks never share a staging slot.
 *
 * Errors.  A device missing or different from the I/O map at load refuses
 * the load, naming the device (iec_io_open()).  A read or write that fails
 * during a cycle raises IEC_FAULT_IO on the task, located at
 * "io <device>.<subdevice>.<channel> <address> errno <n>"; the cycle's
 * programs do not run (input) or its other outputs are not written
 * (output), and the task stops.  When a task goes idle (stop or fault) the
 * outputs it writes go to their safe state: the SAFE value of the I/O map,
 * 0/FALSE by default, nothing for SAFE HOLD.  At load and unload every
 * bound output goes to its safe state.
 *
 * Interrupts.  An INTERRUPT of the I/O map wakes the event tasks whose
 * SINGLE variable is at its address.  The provider requests the line at
 * load, after the task threads exist (iec_io_irq_on()), with its own
 * primary handler (hard interrupt context, IRQF_ONESHOT: it acknowledges
 * the device, stamps the time, returns IRQ_WAKE_THREAD) and
 * iec_io_irq_thread() as the threaded handler: on PREEMPT_RT it runs in
 * the line's irq/N thread (SCHED_FIFO 50, above the PLC tasks), marks each
 * task's event pending with the stamp as its release and wakes its thread.
 * Unload frees the line first (iec_io_irq_off(): free_irq() waits for a
 * running handler), then stops the task threads.  Each line's handled
 * interrupts are counted (the threaded side) and shown in iec_io.
 *
 * User space.  A device user space reaches (iec_io_user.c's character
 * device) is made reachable by iec_io_expose() as the module init's very
 * last step, after everything else that can fail (devices, task threads,
 * interrupt lines), and unreachable by iec_io_withdraw() as the exit's
 * first: an open() cannot take a reference on a module whose init then
 * fails, except when a second device's exposure fails after a first one's:
 * the failed init then waits for such an opener to let go of the module
 * (iec_io_settle()).
 *
 * The hot path.  The devices a task's inputs and outputs use, each once,
 * are generated beside the task's bindings (struct iec_io_set): a cycle
 * asks only those for cycle_in()/cycle_out(), without a walk of the
 * bindings.
 *
 * Scaling: a digital channel is 0/1 in a BOOL; an analog channel's raw
 * sample 0..maxdata is the value of an integer variable, or, in a REAL or
 * LREAL (phys), the physical value lo + raw * (hi - lo) / maxdata of the
 * channel's range, written back by the inverse, rounded and clamped
 * (iec_io_real.c, built with the FPU flags: the conversions run between
 * kernel_fpu_begin() and kernel_fpu_end(), under the image lock, which
 * only disables preemption a little longer).  An integer output's value is
 * clamped to 0..maxdata before it is written.
 *
 * Last values.  Each binding keeps the raw sample it last exchanged with
 * its device: the one read (before a force of the input replaces it in
 * the variable), the one written (a forced output's forced value, clamped
 * or scaled), or the safe value written on stop, fault, load and unload.
 * /sys/module/<resource module>/iec_io shows them, one line a binding:
 * "<address> <device.subdevice.channel> <raw>", "-" for none yet; then
 * one line an interrupt source: "irq <address> <device.source> <line>
 * <interrupts handled since the load>".  They
 * are not the variables' values: a forced input, a scaled REAL, a clamped
 * output, a safe state or a failed read each make the two differ.
 */
#include <linux/delay.h>
#include <linux/errno.h>
#include <linux/interrupt.h>
#include <linux/jiffies.h>
#include <linux/kernel.h>
#include <linux/minmax.h>
#include <linux/module.h>
#include <linux/string.h>
#include <linux/sysfs.h>
#include <asm/fpu/api.h>

#include "iec_kmod.h"
#include "iec_io_real.h"

/* 1 when a binding is REAL-scaled: the module links iec_io_real.o */
#ifndef IEC_IO_PHYS
#define IEC_IO_PHYS 0
#endif

enum iec_io_kind { IEC_IO_AI, IEC_IO_AO, IEC_IO_DI, IEC_IO_DO, IEC_IO_DIO };

struct iec_io_dev;
struct iec_io_bind;
struct iec_io_irq;

/* A provider: how a kind of device is reached. */
struct iec_io_provider {
	const char *name;
	/* module init, process context, may sleep: 0 or -errno (why: text) */
	int (*open)(struct iec_io_dev *d, const char **why);
	void (*close)(struct iec_io_dev *d);
	/* module init: does the device have this channel as the map says? */
	int (*check)(struct iec_io_dev *d, const struct iec_io_bind *b,
		     const char **why);
	/* task thread, preemptible, no lock held: one sample */
	int (*read)(struct iec_io_dev *d, const struct iec_io_bind *b, u32 *raw);
	int (*write)(struct iec_io_dev *d, const struct iec_io_bind *b, u32 raw);
	/*
	 * Interrupt sources (NULL: none).  irq_on, module init, may sleep:
	 * request q->line with the provider's primary handler and
	 * iec_io_irq_thread, then let the device raise it; irq_off undoes it
	 * and returns when no handler runs any more.
	 */
	int (*irq_on)(struct iec_io_dev *d, struct iec_io_irq *q, const char **why);
	void (*irq_off)(struct iec_io_dev *d, struct iec_io_irq *q);
	/*
	 * Optional, for a device exchanged a whole cycle at a time
	 * (iec_io_user.c); task thread, no lock held.  cycle_in() comes
	 * before the reads of a task cycle that reads the device (an error
	 * faults the task, located at "io <device>: <why>"), cycle_out()
	 * after the writes of a cycle that writes it (t: that task) and
	 * after a safe state (safe true; t NULL).
	 */
	int (*cycle_in)(struct iec_io_dev *d, struct iec_task *t,
			const char **why);
	void (*cycle_out)(struct iec_io_dev *d, struct iec_task *t, bool safe);
	/*
	 * Optional, for a device user space reaches (iec_io_user.c).
	 * expose(), module init's last step, may sleep: make it reachable
	 * (0 or -errno, why: text); withdraw() makes it unreachable again
	 * (exit's first step, or a failed init), after which no open() of
	 * it is under way in the provider's code.
	 */
	int (*expose)(struct iec_io_dev *d, const char **why);
	void (*withdraw)(struct iec_io_dev *d);
};

struct iec_io_dev {
	const char *name;		/* the I/O map's device name */
	const struct iec_io_provider *prov;
	unsigned int minor;
	void *handle;			/* the provider's */
	bool exposed;			/* expose() done, withdraw() not yet */
};

struct iec_io_bind {
	const char *address;		/* %IW2 */
	const char *channel;		/* daq.0.3 */
	u16 dev;			/* index in the devices */
	u16 subdev;
	u16 chan;
	u8 kind;			/* enum iec_io_kind */
	u8 input;
	u8 range;
	u8 hold;			/* SAFE HOLD */
	u32 maxdata;			/* 1 for a digital channel */
	u32 safe;			/* raw safe value */
	void *var;			/* the located variable */
	u8 size;			/* its size: 1, 2, 4 or 8 */
	u8 is_signed;
	u8 phys;			/* a REAL/LREAL: scaled by .scale */
	struct iec_io_scale scale;	/* phys: the range (iec_io_real.h) */
};

/*
 * A task's bound inputs, or its bound outputs (generated beside the task):
 * the bindings, their staging array and the devices they use.
 */
struct iec_io_set {
	const u16 *idx;			/* indexes in the bindings */
	u32 *raw;			/* staging: one sample a binding */
	u32 n;
	const u16 *devs;		/* the devices idx[] use, each once */
	u32 ndevs;
};

/* An interrupt source bound to the event tasks of one SINGLE variable. */
struct iec_io_irq {
	const char *address;		/* %IX9.0 */
	const char *source;		/* lpt.ACK */
	u16 dev;
	u16 line;			/* the IRQ number */
	const u16 *tasks;		/* indexes in the resource's tasks */
	u32 ntasks;
	/* runtime */
	struct iec_resource *res;
	unsigned long base;		/* the provider's (an I/O port base) */
	ktime_t stamp;			/* set by the primary handler */
	u64 count;			/* handled interrupts (threaded side; iec_io) */
	bool on;
};

struct iec_io {
	const char *resource;
	struct iec_io_dev *devs;
	u32 ndevs;
	const struct iec_io_bind *binds;
	u32 nbinds;
	u32 nopen;			/* devices opened so far */
	/* per task: the text its IEC_FAULT_IO points at */
	char (*fault_text)[64];
	struct iec_io_irq *irqs;
	u32 nirqs;
	/* per binding: the raw sample last exchanged with the device, valid
	 * once seen[] is set (the sysfs file iec_io) */
	u32 *last;
	u8 *seen;
	bool exposed;			/* a device was exposed (iec_io_settle) */
};

static void iec_io_seen(struct iec_io *io, const struct iec_io_bind *b, u32 raw)
{
	u32 i = b - io->binds;

	WRITE_ONCE(io->last[i], raw);
	smp_wmb();	/* the value before the mark (iec_io_show) */
	WRITE_ONCE(io->seen[i], 1);
}

static u32 iec_io_get(const struct iec_io_bind *b)
{
	s64 v;

	switch (b->size) {
	case 1:
		v = b->is_signed ? *(s8 *)b->var : *(u8 *)b->var;
		break;
	case 2:
		v = b->is_signed ? *(s16 *)b->var : *(u16 *)b->var;
		break;
	case 4:
		v = b->is_signed ? *(s32 *)b->var : *(u32 *)b->var;
		break;
	default:
		if (b->is_signed)
			v = *(s64 *)b->var;
		else
			v = (s64)min_t(u64, *(u64 *)b->var, U32_MAX);
		break;
	}
	if (b->maxdata == 1)
		return v != 0;
	return (u32)clamp_t(s64, v, 0, b->maxdata);
}

static void iec_io_put(const struct iec_io_bind *b, u32 raw)
{
	switch (b->size) {
	case 1:
		*(u8 *)b->var = (u8)raw;
		break;
	case 2:
		*(u16 *)b->var = (u16)raw;
		break;
	case 4:
		*(u32 *)b->var = raw;
		break;
	default:
		*(u64 *)b->var = raw;
		break;
	}
}

static void iec_io_fault(struct iec_io *io, struct iec_task *t,
			 const struct iec_io_bind *b, int err)
{
	char *text = io->fault_text[t - t->res->tasks];

	if (t->ctx.fault != IEC_FAULT_NONE)
		return;
	snprintf(text, sizeof(io->fault_text[0]), "io %s %s errno %d",
		 b->channel, b->address, -err);
	iec_fault_raise(&t->ctx, IEC_FAULT_IO);
	iec_fault_locate(&t->ctx, text, 0);
}

/* Does a binding use device dev?  (load and unload only) */
static bool iec_io_used(const struct iec_io *io, u32 dev)
{
	u32 i;

	for (i = 0; i < io->nbinds; i++)
		if (io->binds[i].dev == dev)
			return true;
	return false;
}

/* cycle_out() of the devices of s that have one (s NULL: every used one) */
static void iec_io_cycle_out(struct iec_io *io, struct iec_task *t,
			     const struct iec_io_set *s, bool safe)
{
	u32 j, n = s ? s->ndevs : io->nopen;

	for (j = 0; j < n; j++) {
		u32 k = s ? s->devs[j] : j;
		struct iec_io_dev *d = &io->devs[k];

		if (!d->prov->cycle_out || k >= io->nopen)
			continue;
		if (s || iec_io_used(io, k))
			d->prov->cycle_out(d, t, safe);
	}
}

/*
 * Steps 1, 2, 4 and 5 (__maybe_unused: a resource whose tasks only read, or
 * only write, or only wait for interrupts uses some of them).
 *
 * Step 1: the task's inputs s into s->raw[]; false (and a fault) on an
 * error.
 */
static __maybe_unused bool iec_io_read(struct iec_io *io, struct iec_task *t,
				       const struct iec_io_set *s)
{
	const char *why = "";
	u32 i;

	for (i = 0; i < s->ndevs; i++) {
		struct iec_io_dev *d = &io->devs[s->devs[i]];
		char *text = io->fault_text[t - t->res->tasks];
		int ret;

		if (!d->prov->cycle_in)
			continue;
		ret = d->prov->cycle_in(d, t, &why);
		if (ret < 0) {
			if (t->ctx.fault == IEC_FAULT_NONE) {
				snprintf(text, sizeof(io->fault_text[0]),
					 "io %s: %s errno %d", d->name, why, -ret);
				iec_fault_raise(&t->ctx, IEC_FAULT_IO);
				iec_fault_locate(&t->ctx, text, 0);
			}
			return false;
		}
	}
	for (i = 0; i < s->n; i++) {
		const struct iec_io_bind *b = &io->binds[s->idx[i]];
		struct iec_io_dev *d = &io->devs[b->dev];
		int ret = d->prov->read(d, b, &s->raw[i]);

		if (ret < 0) {
			iec_io_fault(io, t, b, ret);
			return false;
		}
		iec_io_seen(io, b, s->raw[i]);
	}
	return true;
}

/* Step 2, under the image lock: the staged inputs into their variables. */
static __maybe_unused void iec_io_store(struct iec_io *io,
					const struct iec_io_set *s)
{
	bool fpu = false;
	u32 i;

	for (i = 0; i < s->n; i++) {
		const struct iec_io_bind *b = &io->binds[s->idx[i]];

		if (!IEC_IO_PHYS || !b->phys) {
			iec_io_put(b, s->raw[i]);
			continue;
		}
		if (!fpu) {
			kernel_fpu_begin();
			fpu = true;
		}
		iec_io_real_store(&b->scale, b->var, b->size, s->raw[i]);
	}
	if (fpu)
		kernel_fpu_end();
}

/* Step 4, under the image lock: the task's outputs s into s->raw[]. */
static __maybe_unused void iec_io_stage(struct iec_io *io,
					const struct iec_io_set *s)
{
	bool fpu = false;
	u32 i;

	for (i = 0; i < s->n; i++) {
		const struct iec_io_bind *b = &io->binds[s->idx[i]];

		if (!IEC_IO_PHYS || !b->phys) {
			s->raw[i] = iec_io_get(b);
			continue;
		}
		if (!fpu) {
			kernel_fpu_begin();
			fpu = true;
		}
		s->raw[i] = iec_io_real_load(&b->scale, b->var, b->size);
	}
	if (fpu)
		kernel_fpu_end();
}

/* Step 5: s->raw[] to the devices; a fault on the first error. */
static __maybe_unused void iec_io_write(struct iec_io *io, struct iec_task *t,
					const struct iec_io_set *s)
{
	u32 i;

	for (i = 0; i < s->n; i++) {
		const struct iec_io_bind *b = &io->binds[s->idx[i]];
		struct iec_io_dev *d = &io->devs[b->dev];
		int ret = d->prov->write(d, b, s->raw[i]);

		if (ret < 0) {
			iec_io_fault(io, t, b, ret);
			return;
		}
		iec_io_seen(io, b, s->raw[i]);
	}
	iec_io_cycle_out(io, t, s, false);
}

/* The outputs of s (every output: s NULL) to their safe state; best effort. */
static void iec_io_safe(struct iec_io *io, const struct iec_io_set *s)
{
	u32 i, n = s ? s->n : io->nbinds;

	for (i = 0; i < n; i++) {
		const struct iec_io_bind *b = &io->binds[s ? s->idx[i] : i];
		struct iec_io_dev *d = &io->devs[b->dev];

		if (b->input || b->hold || b->dev >= io->nopen)
			continue;
		if (d->prov->write(d, b, b->safe) < 0)
			pr_warn_ratelimited("iec2kmod: resource %s: %s %s: safe value not written\n",
					    io->resource, b->channel, b->address);
		else
			iec_io_seen(io, b, b->safe);
	}
	iec_io_cycle_out(io, NULL, s, true);
}

/*
 * /sys/module/<resource module>/iec_io: per binding, the raw sample last
 * exchanged with its device (plc-manager status).  Root-only, as
 * iec_latency.
 */
static struct iec_io *iec_io_this;

static ssize_t iec_io_show(struct kobject *kobj, struct kobj_attribute *attr,
			   char *buf)
{
	struct iec_io *io = iec_io_this;
	int len = 0;
	u32 i;

	for (i = 0; io && i < io->nbinds; i++) {
		const struct iec_io_bind *b = &io->binds[i];

		if (len > PAGE_SIZE - 128) {
			len += sysfs_emit_at(buf, len, "...\n");
			break;
		}
		if (READ_ONCE(io->seen[i])) {
			smp_rmb();	/* pairs with iec_io_seen() */
			len += sysfs_emit_at(buf, len, "%s %s %u\n", b->address,
					     b->channel, READ_ONCE(io->last[i]));
		} else {
			len += sysfs_emit_at(buf, len, "%s %s -\n", b->address,
					     b->channel);
		}
	}
	for (i = 0; io && i < io->nirqs; i++) {
		const struct iec_io_irq *q = &io->irqs[i];

		if (len > PAGE_SIZE - 128) {
			len += sysfs_emit_at(buf, len, "...\n");
			break;
		}
		len += sysfs_emit_at(buf, len, "irq %s %s %u %llu\n", q->address,
				     q->source, q->line, READ_ONCE(q->count));
	}
	return len;
}

static struct kobj_attribute iec_io_attr = __ATTR(iec_io, 0400, iec_io_show, NULL);

static void iec_io_close(struct iec_io *io)
{
	while (io->nopen) {
		struct iec_io_dev *d = &io->devs[--io->nopen];

		d->prov->close(d);
	}
}

/* Module init: every device present and as the map says, or -errno. */
static int iec_io_open(struct iec_io *io)
{
	const char *why = "";
	u32 i;
	int ret;

	for (i = 0; i < io->ndevs; i++) {
		struct iec_io_dev *d = &io->devs[i];

		ret = d->prov->open(d, &why);
		if (ret) {
			pr_err("iec2kmod: resource %s: device %s (%s minor %u): %s; not loading\n",
			       io->resource, d->name, d->prov->name, d->minor, why);
			goto err;
		}
		io->nopen = i + 1;
	}
	for (i = 0; i < io->nbinds; i++) {
		const struct iec_io_bind *b = &io->binds[i];
		struct iec_io_dev *d = &io->devs[b->dev];

		ret = d->prov->check(d, b, &why);
		if (ret) {
			pr_err("iec2kmod: resource %s: device %s: %s of %s: %s; not loading\n",
			       io->resource, d->name, b->channel, b->address, why);
			goto err;
		}
	}
	iec_io_safe(io, NULL);		/* outputs start in their safe state */
	iec_io_this = io;
	if (sysfs_create_file(&THIS_MODULE->mkobj.kobj, &iec_io_attr.attr))
		pr_warn("iec2kmod: resource %s: no iec_io file in sysfs\n", io->resource);
	return 0;
err:
	iec_io_close(io);
	return ret;
}

/*
 * The threaded handler of every interrupt source: runs in the line's irq
 * thread (preemptible on PREEMPT_RT, never sleeps here).  The primary
 * handler stamped the interrupt; the stamp is each task's release.
 * (__maybe_unused: only a provider with interrupts refers to it.)
 */
static __maybe_unused irqreturn_t iec_io_irq_thread(int irq, void *arg)
{
	struct iec_io_irq *q = arg;
	ktime_t stamp = READ_ONCE(q->stamp);
	u32 i;

	WRITE_ONCE(q->count, q->count + 1);	/* iec_io_show() reads it */
	for (i = 0; i < q->ntasks; i++) {
		struct iec_task *t = &q->res->tasks[q->tasks[i]];

		if (!t->thread)
			continue;
		WRITE_ONCE(t->event_time, stamp);
		smp_wmb();	/* the release before the event (iec_wait_event) */
		WRITE_ONCE(t->event_pending, true);
		wake_up_process(t->thread);
	}
	return IRQ_HANDLED;
}

static void iec_io_irq_off(struct iec_io *io)
{
	u32 i;

	for (i = io->nirqs; i-- > 0;) {
		struct iec_io_irq *q = &io->irqs[i];
		struct iec_io_dev *d = &io->devs[q->dev];

		if (!q->on)
			continue;
		d->prov->irq_off(d, q);	/* free_irq(): no handler runs after it */
		q->on = false;
		pr_info("iec2kmod: resource %s: IRQ %u (%s) released after %llu interrupts\n",
			io->resource, q->line, q->source, q->count);
	}
}

/* Module init, the task threads created: the interrupt lines, or -errno. */
static int iec_io_irq_on(struct iec_io *io, struct iec_resource *res)
{
	const char *why = "";
	u32 i;
	int ret;

	for (i = 0; i < io->nirqs; i++) {
		struct iec_io_irq *q = &io->irqs[i];
		struct iec_io_dev *d = &io->devs[q->dev];

		q->res = res;
		ret = d->prov->irq_on ? d->prov->irq_on(d, q, &why) : -EOPNOTSUPP;
		if (ret) {
			pr_err("iec2kmod: resource %s: interrupt %s (IRQ %u) of %s: %s (errno %d); not loading\n",
			       io->resource, q->source, q->line, q->address,
			       d->prov->irq_on ? why : "the provider has no interrupts", -ret);
			iec_io_irq_off(io);
			return ret;
		}
		q->on = true;
	}
	return 0;
}

/* Exit's first step, or a failed init: no device reachable any more. */
static void iec_io_withdraw(struct iec_io *io)
{
	u32 i;

	for (i = io->ndevs; i-- > 0;) {
		struct iec_io_dev *d = &io->devs[i];

		if (!d->exposed)
			continue;
		d->prov->withdraw(d);
		d->exposed = false;
	}
}

/*
 * A failed init's last step, everything undone.  If a device had been
 * exposed, an open() that found it took a reference on this module (the
 * file operations' owner) and keeps it until the VFS drops it, after the
 * provider refused the open (iec_user_fopen(): the module is not live).
 * The module is freed as soon as init returns, so wait, bounded, until the
 * count is back to base, what it was when init began.  Nothing else holds
 * the module then: the task threads are gone and the configuration let
 * the resource go.
 */
static void iec_io_settle(struct iec_io *io, int base)
{
	unsigned long end = jiffies + 5 * HZ;

	if (!io->exposed)
		return;
	while (module_refcount(THIS_MODULE) > base) {
		if (time_after(jiffies, end)) {
			pr_err("iec2kmod: resource %s: a user device's opener still holds the module after 5 s\n",
			       io->resource);
			return;
		}
		usleep_range(1000, 2000);
	}
}

/*
 * Module init's last step: every device user space reaches made reachable,
 * or -errno with none reachable (then undo the rest of init, and
 * iec_io_settle()).
 */
static int iec_io_expose(struct iec_io *io)
{
	const char *why = "";
	u32 i;
	int ret;

	for (i = 0; i < io->ndevs; i++) {
		struct iec_io_dev *d = &io->devs[i];

		if (!d->prov->expose)
			continue;
		ret = d->prov->expose(d, &why);
		if (ret) {
			pr_err("iec2kmod: resource %s: device %s (%s): %s (errno %d); not loading\n",
			       io->resource, d->name, d->prov->name, why, -ret);
			iec_io_withdraw(io);
			return ret;
		}
		d->exposed = true;
		io->exposed = true;
	}
	return 0;
}

/* Module exit, the threads stopped: safe state, then the devices go. */
static void iec_io_exit(struct iec_io *io)
{
	iec_io_withdraw(io);	/* done already, unless init failed before */
	sysfs_remove_file(&THIS_MODULE->mkobj.kobj, &iec_io_attr.attr);
	iec_io_safe(io, NULL);
	iec_io_close(io);
}
