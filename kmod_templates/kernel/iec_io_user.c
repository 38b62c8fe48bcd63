// SPDX-License-Identifier: GPL-2.0-only OR MIT
/*
 * iec_io_user.c - the user-space provider of iec_io.c: a device of the I/O
 * map (DEVICE fb : user INPUTS n OUTPUTS m STALE ms) is a misc character
 * device /dev/iec_io_<config>_<resource>_<device> whose mmap() shares a
 * double-buffered copy of its bound inputs and outputs with a user-space
 * daemon (a fieldbus master, a test harness; manager/iodaemon.py is the
 * reference).  One task exchanges the device (the generator checks it):
 * each of its cycles takes the daemon's latest inputs before copy-in
 * (cycle_in) and publishes the outputs after copy-out (cycle_out).
 *
 * Shared memory, version 1.  Every field in the host's byte order
 * (little-endian on x86-64 and arm64); offsets in bytes.
 *
 *   header, written by the kernel only
 *     0  u32 magic         0x55434549 ("IECU" in memory on little-endian)
 *     4  u16 version       1
 *     6  u16 header_size   128
 *     8  u32 n_in          input slots
 *    12  u32 n_out         output slots
 *    16  u32 in_off        input record 0; record 1 at in_off + in_stride
 *    20  u32 in_stride
 *    24  u32 out_off       output record 0; record 1 at out_off + out_stride
 *    28  u32 out_stride
 *    32  u32 desc_off      slot descriptors: n_in inputs, then n_out outputs
 *    36  u32 stale_ms      0: STALE OFF
 *    40  u64 interval_ns   the exchanging task's interval (0: event task)
 *    48  u32 out_seq       outputs' latch sequence: read record out_seq & 1
 *    52  u32 in_taken      the in_seq of the inputs the kernel took last
 *    56  u32 status        bit 0 SAFE: the outputs are the safe state (task
 *                          not running); bit 1 STALE: the task faulted on
 *                          stale inputs
 *    60  u32 size          bytes mapped
 *   written by the daemon
 *    64  u32 in_seq        inputs' latch sequence: the kernel reads record
 *                          in_seq & 1
 *    68..127               reserved, 0
 *   slot descriptor (32 bytes): char address[24] (NUL-padded, e.g. "%QW0";
 *     empty: slot not bound), u16 type (1 BOOL 2 SINT 3 INT 4 DINT 5 USINT
 *     6 UINT 7 UDINT 8 BYTE 9 WORD 10 DWORD 11 REAL; 0 not bound), u16 0,
 *     u32 0
 *   input record: u64 tag (the daemon's, e.g. the output cycle it answers),
 *     then n_in u32 slots
 *   output record: u64 cycle (the task's cycle count since the load that
 *     produced it), u64 in_tag (tag of the inputs that cycle read), u32
 *     flags (bit 0 SAFE), u32 0, then n_out u32 slots
 *
 * A slot holds 32 bits: a BOOL 0/1 (an input: non-zero is TRUE), a signed
 * integer sign-extended, an unsigned one or a bit string zero-extended, a
 * REAL its IEEE-754 bits.  An input out of its variable's range is
 * saturated (UINT 70000 gives 65535).
 *
 * Consistency: both directions are a latch sequence (Linux's
 * seqcount_latch): the writer increments seq (now odd: readers use record
 * 1), writes record 0, increments seq (even: readers use record 0), writes
 * record 1.  A reader reads seq, copies record seq & 1, and retries if seq
 * changed meanwhile.  So the writer never waits for the reader, the reader
 * never sees a half-written record, and a writer that dies mid-update
 * leaves the other record whole.  The daemon is the inputs' only writer
 * (one process may open the device read-write; read-only openers may
 * watch); the kernel the outputs'.  What a daemon gets: the outputs of one
 * task cycle, all from that cycle, with its cycle number; its inputs all
 * reach the program in the same cycle, together.  The kernel tries a record
 * three times, then keeps the previous inputs for this cycle (a daemon
 * rewriting faster than a memcpy).  The stores need release order (a C
 * daemon: __atomic_store_n(.., __ATOMIC_RELEASE) on in_seq, loads of
 * out_seq with acquire); x86's stores and loads are ordered, which the
 * Python reference daemon relies on.
 *
 * In step: read() of 8 bytes blocks until a publication (a cycle's outputs
 * or a safe state) this file has not been told of and returns the count of
 * publications (u64); poll() says POLLIN then.  O_NONBLOCK: -EAGAIN.  A
 * device whose task writes none of its outputs publishes at the start of
 * each cycle instead, after taking the inputs (its record has the cycle
 * and in_tag): a daemon of an input-only device runs in step too.
 *
 * A slow or absent daemon: a cycle without new inputs keeps the previous
 * ones (a program sees its input unchanged; the output record's in_tag
 * tells the daemon which inputs a cycle used).  When the daemon has
 * published nothing for STALE ms (counted from the task's start, then from
 * its last publication), the task faults with IEC_FAULT_IO "io <device>:
 * inputs stale errno 110" and its outputs go to their safe state; STALE
 * OFF keeps the last inputs for ever.
 *
 * PREEMPT_RT: cycle_in/cycle_out run in the task thread outside the image
 * lock (iec_io.c); they copy at most 4 KiB, take only this device's
 * spinlock_t (a sleeping lock on RT, never taken in atomic context) and
 * wake the readers.  The open file holds the module (fops owner): the
 * resource cannot be removed while a daemon holds the device or a mapping
 * of it (delete_module says "in use").
 *
 * A failed load: the device node is registered by iec_user_expose(), the
 * module init's very last step (iec_io_expose(), after the other devices,
 * the task threads and the interrupt lines), and deregistered first at
 * exit.  So with one user device, a load that fails never showed the node;
 * with several, only the failure of a later device's registration can
 * follow an earlier one's.  An open() racing it is refused (the module is
 * not live until init returns), and the failed init waits for its module
 * reference to go (iec_io_settle()): no file outlives a failed load.
 */
#include <linux/atomic.h>
#include <linux/fs.h>
#include <linux/miscdevice.h>
#include <linux/mm.h>
#include <linux/poll.h>
#include <linux/slab.h>
#include <linux/spinlock.h>
#include <linux/uaccess.h>
#include <linux/vmalloc.h>
#include <linux/wait.h>

#define IEC_USER_MAGIC		0x55434549U
#define IEC_USER_VERSION	1
#define IEC_USER_DESC_SIZE	32
#define IEC_USER_TRIES		3
#define IEC_USER_SAFE		BIT(0)
#define IEC_USER_STALE		BIT(1)

enum iec_user_type {
	IEC_USER_BOOL = 1, IEC_USER_SINT, IEC_USER_INT, IEC_USER_DINT,
	IEC_USER_USINT, IEC_USER_UINT, IEC_USER_UDINT, IEC_USER_BYTE,
	IEC_USER_WORD, IEC_USER_DWORD, IEC_USER_REAL,
};

struct iec_user_hdr {
	u32 magic;
	u16 version;
	u16 header_size;
	u32 n_in;
	u32 n_out;
	u32 in_off;
	u32 in_stride;
	u32 out_off;
	u32 out_stride;
	u32 desc_off;
	u32 stale_ms;
	u64 interval_ns;
	u32 out_seq;
	u32 in_taken;
	u32 status;
	u32 size;
	/* written by the daemon */
	u32 in_seq;
	u32 reserved[15];
};

static_assert(offsetof(struct iec_user_hdr, interval_ns) == 40);
static_assert(offsetof(struct iec_user_hdr, in_seq) == 64);
static_assert(sizeof(struct iec_user_hdr) == 128);

struct iec_user_desc {
	char address[24];
	u16 type;
	u16 flags;
	u32 reserved;
};

static_assert(sizeof(struct iec_user_desc) == IEC_USER_DESC_SIZE);

struct iec_user_slot {
	const char *address;		/* "" : not bound */
	u16 type;			/* enum iec_user_type, 0: not bound */
};

/* A user device: the generator's description, then the runtime state. */
struct iec_user_dev {
	const char *node;		/* iec_io_<config>_<resource>_<device> */
	u32 nin;
	u32 nout;
	u32 stale_ms;
	s64 interval_ns;
	const struct iec_user_slot *slots;	/* nin inputs, nout outputs */
	bool publish_in;		/* its task writes none of its outputs */

	/* the layout: the kernel never reads it back from the shared header */
	u32 in_off, in_stride, out_off, out_stride;
	struct miscdevice misc;
	void *mem;			/* vmalloc_user(): shared, zeroed */
	struct iec_user_hdr *hdr;
	u32 size;
	u32 *in_vals;			/* the inputs taken (task thread) */
	u32 *in_next;			/* a record being copied */
	u32 *out_vals;			/* the outputs written this cycle */
	u64 in_tag;
	u32 in_seq;			/* the daemon's in_seq taken */
	ktime_t fresh;			/* inputs last taken (or task start) */
	u64 starts;			/* the task's starts at the last cycle */
	u64 cycle;
	u32 out_seq;
	u32 status;
	spinlock_t lock;		/* serialises the output publications */
	atomic64_t published;
	wait_queue_head_t wq;
	atomic_t writer;		/* a read-write opener */
};

/* what an open file knows */
struct iec_user_file {
	struct iec_user_dev *u;
	u64 seen;			/* publications told by read()/poll() */
	bool writer;
};

static u32 iec_user_stride(u32 head, u32 n)
{
	return ALIGN(head + 4 * n, 8);
}

static void *iec_user_in_rec(struct iec_user_dev *u, u32 k)
{
	return u->mem + u->in_off + k * u->in_stride;
}

static void *iec_user_out_rec(struct iec_user_dev *u, u32 k)
{
	return u->mem + u->out_off + k * u->out_stride;
}

/* ---------------------------------------------------------------- file -- */

static int iec_user_fopen(struct inode *inode, struct file *f)
{
	struct miscdevice *m = f->private_data;
	struct iec_user_dev *u = container_of(m, struct iec_user_dev, misc);
	struct iec_user_file *uf;

	/* a load still under way may fail: no file may outlive it */
	if (READ_ONCE(THIS_MODULE->state) != MODULE_STATE_LIVE)
		return -EAGAIN;
	uf = kzalloc(sizeof(*uf), GFP_KERNEL);
	if (!uf)
		return -ENOMEM;
	uf->u = u;
	if (f->f_mode & FMODE_WRITE) {
		if (atomic_cmpxchg(&u->writer, 0, 1)) {
			kfree(uf);
			return -EBUSY;	/* the inputs have one writer */
		}
		uf->writer = true;
	}
	uf->seen = atomic64_read(&u->published);
	f->private_data = uf;
	return stream_open(inode, f);
}

static int iec_user_release(struct inode *inode, struct file *f)
{
	struct iec_user_file *uf = f->private_data;

	if (uf->writer)
		atomic_set(&uf->u->writer, 0);
	kfree(uf);
	return 0;
}

static ssize_t iec_user_fread(struct file *f, char __user *buf, size_t len,
			      loff_t *pos)
{
	struct iec_user_file *uf = f->private_data;
	struct iec_user_dev *u = uf->u;
	u64 n;
	int ret;

	if (len < sizeof(n))
		return -EINVAL;
	if (atomic64_read(&u->published) == uf->seen) {
		if (f->f_flags & O_NONBLOCK)
			return -EAGAIN;
		ret = wait_event_interruptible(u->wq, atomic64_read(&u->published) != uf->seen);
		if (ret)
			return ret;
	}
	n = atomic64_read(&u->published);
	uf->seen = n;
	if (copy_to_user(buf, &n, sizeof(n)))
		return -EFAULT;
	return sizeof(n);
}

static __poll_t iec_user_poll(struct file *f, struct poll_table_struct *pt)
{
	struct iec_user_file *uf = f->private_data;
	struct iec_user_dev *u = uf->u;

	poll_wait(f, &u->wq, pt);
	return atomic64_read(&u->published) != uf->seen ? EPOLLIN | EPOLLRDNORM : 0;
}

static int iec_user_mmap(struct file *f, struct vm_area_struct *vma)
{
	struct iec_user_file *uf = f->private_data;

	return remap_vmalloc_range(vma, uf->u->mem, vma->vm_pgoff);
}

static const struct file_operations iec_user_fops = {
	.owner = THIS_MODULE,
	.open = iec_user_fopen,
	.release = iec_user_release,
	.read = iec_user_fread,
	.poll = iec_user_poll,
	.mmap = iec_user_mmap,
	.llseek = no_llseek,
};

/* ------------------------------------------------------------ provider -- */

/* what iec_user_open() allocates; a failed open and close both free it */
static void iec_user_free(struct iec_user_dev *u)
{
	vfree(u->mem);
	kfree(u->in_vals);
	kfree(u->in_next);
	kfree(u->out_vals);
	u->mem = NULL;
	u->in_vals = NULL;
	u->in_next = NULL;
	u->out_vals = NULL;
}

static int iec_user_open(struct iec_io_dev *d, const char **why)
{
	struct iec_user_dev *u = d->handle;
	struct iec_user_hdr *h;
	u32 desc_off = sizeof(*h);
	u32 in_off = desc_off + IEC_USER_DESC_SIZE * (u->nin + u->nout);
	u32 in_stride = iec_user_stride(8, u->nin);
	u32 out_off = in_off + 2 * in_stride;
	u32 out_stride = iec_user_stride(24, u->nout);
	u32 i;
	int ret;

	u->size = PAGE_ALIGN(out_off + 2 * out_stride);
	u->mem = vmalloc_user(u->size);
	u->in_vals = kcalloc(u->nin + 1, sizeof(u32), GFP_KERNEL);
	u->in_next = kcalloc(u->nin + 1, sizeof(u32), GFP_KERNEL);
	u->out_vals = kcalloc(u->nout + 1, sizeof(u32), GFP_KERNEL);
	if (!u->mem || !u->in_vals || !u->in_next || !u->out_vals) {
		*why = "out of memory for its shared area";
		ret = -ENOMEM;
		goto err;
	}
	h = u->mem;
	u->hdr = h;
	u->in_off = in_off;
	u->in_stride = in_stride;
	u->out_off = out_off;
	u->out_stride = out_stride;
	h->magic = IEC_USER_MAGIC;
	h->version = IEC_USER_VERSION;
	h->header_size = sizeof(*h);
	h->n_in = u->nin;
	h->n_out = u->nout;
	h->in_off = in_off;
	h->in_stride = in_stride;
	h->out_off = out_off;
	h->out_stride = out_stride;
	h->desc_off = desc_off;
	h->stale_ms = u->stale_ms;
	h->interval_ns = u->interval_ns;
	h->size = u->size;
	for (i = 0; i < u->nin + u->nout; i++) {
		struct iec_user_desc *desc = u->mem + desc_off + i * sizeof(*desc);

		strscpy(desc->address, u->slots[i].address, sizeof(desc->address));
		desc->type = u->slots[i].type;
	}
	u->status = IEC_USER_SAFE;
	h->status = u->status;
	spin_lock_init(&u->lock);
	init_waitqueue_head(&u->wq);
	atomic64_set(&u->published, 0);
	atomic_set(&u->writer, 0);
	return 0;
err:
	iec_user_free(u);
	return ret;
}

/* module exit or failed init, the device withdrawn: no file is open */
static void iec_user_close(struct iec_io_dev *d)
{
	iec_user_free(d->handle);
}

/* module init's last step (iec_io_expose()): /dev/<node> appears */
static int iec_user_expose(struct iec_io_dev *d, const char **why)
{
	struct iec_user_dev *u = d->handle;
	int ret;

	u->misc.minor = MISC_DYNAMIC_MINOR;
	u->misc.name = u->node;
	u->misc.fops = &iec_user_fops;
	u->misc.mode = 0600;
	ret = misc_register(&u->misc);
	if (ret)
		*why = "its character device cannot be registered (is the name taken?)";
	return ret;
}

/*
 * exit's first step, or a failed init: after misc_deregister() (misc_open()
 * runs under the same mutex) no open() is in iec_user_fopen() and none can
 * find the device
 */
static void iec_user_withdraw(struct iec_io_dev *d)
{
	struct iec_user_dev *u = d->handle;

	misc_deregister(&u->misc);
}

static int iec_user_check(struct iec_io_dev *d, const struct iec_io_bind *b,
			  const char **why)
{
	struct iec_user_dev *u = d->handle;
	u32 n = b->input ? u->nin : u->nout;

	if (b->chan >= n || !u->slots[b->input ? b->chan : u->nin + b->chan].type) {
		*why = "the binding has no slot in the device";
		return -EINVAL;
	}
	return 0;
}

/* An input slot as the raw value of iec_io_put(): saturated to its type. */
static u32 iec_user_in(u16 type, u32 v)
{
	switch (type) {
	case IEC_USER_BOOL:
		return v != 0;
	case IEC_USER_SINT:
		return (u32)clamp_t(s32, (s32)v, S8_MIN, S8_MAX);
	case IEC_USER_INT:
		return (u32)clamp_t(s32, (s32)v, S16_MIN, S16_MAX);
	case IEC_USER_USINT:
	case IEC_USER_BYTE:
		return min_t(u32, v, U8_MAX);
	case IEC_USER_UINT:
	case IEC_USER_WORD:
		return min_t(u32, v, U16_MAX);
	default:		/* DINT, UDINT, DWORD, REAL: the 32 bits */
		return v;
	}
}

/* iec_io_get()'s raw value (the variable's bits, zero-extended) as a slot */
static u32 iec_user_out(u16 type, u32 raw)
{
	switch (type) {
	case IEC_USER_SINT:
		return (u32)(s32)(s8)raw;
	case IEC_USER_INT:
		return (u32)(s32)(s16)raw;
	default:
		return raw;
	}
}

static int iec_user_read(struct iec_io_dev *d, const struct iec_io_bind *b,
			 u32 *raw)
{
	struct iec_user_dev *u = d->handle;

	*raw = iec_user_in(u->slots[b->chan].type, u->in_vals[b->chan]);
	return 0;
}

static int iec_user_write(struct iec_io_dev *d, const struct iec_io_bind *b,
			  u32 raw)
{
	struct iec_user_dev *u = d->handle;

	u->out_vals[b->chan] = iec_user_out(u->slots[u->nin + b->chan].type, raw);
	return 0;
}

static void iec_user_fill(struct iec_user_dev *u, u32 k, u32 flags)
{
	u32 *rec = iec_user_out_rec(u, k);
	u32 i;

	WRITE_ONCE(*(u64 *)rec, u->cycle);
	WRITE_ONCE(*(u64 *)(rec + 2), u->in_tag);
	WRITE_ONCE(rec[4], flags);
	for (i = 0; i < u->nout; i++)
		WRITE_ONCE(rec[6 + i], u->out_vals[i]);
}

/* A publication: the output record, whole, then the readers woken. */
static void iec_user_publish(struct iec_user_dev *u, struct iec_task *t,
			     u32 flags)
{
	struct iec_user_hdr *h = u->hdr;

	spin_lock(&u->lock);
	if (t)
		u->cycle = t->stats.cycles + 1;	/* counted at the cycle's end */
	smp_store_release(&h->out_seq, ++u->out_seq);	/* odd: record 1 */
	smp_wmb();
	iec_user_fill(u, 0, flags);
	smp_store_release(&h->out_seq, ++u->out_seq);	/* even: record 0 */
	smp_wmb();
	iec_user_fill(u, 1, flags);
	u->status = (u->status & ~IEC_USER_SAFE) | flags;
	WRITE_ONCE(h->status, u->status);
	spin_unlock(&u->lock);
	atomic64_inc(&u->published);
	wake_up_interruptible(&u->wq);
}

/* The start of a cycle: the daemon's latest complete inputs, or staleness. */
static int iec_user_cycle_in(struct iec_io_dev *d, struct iec_task *t,
			     const char **why)
{
	struct iec_user_dev *u = d->handle;
	struct iec_user_hdr *h = u->hdr;
	ktime_t now = ktime_get();
	u32 seq = smp_load_acquire(&h->in_seq);
	u32 try, i;

	if (READ_ONCE(t->stats.starts) != u->starts) {	/* STALE counts from a start */
		u->starts = READ_ONCE(t->stats.starts);
		u->fresh = now;
	}
	for (try = 0; seq != u->in_seq && try < IEC_USER_TRIES; try++) {
		const u32 *rec = iec_user_in_rec(u, seq & 1);
		u64 tag = READ_ONCE(*(const u64 *)rec);
		u32 again;

		for (i = 0; i < u->nin; i++)
			u->in_next[i] = READ_ONCE(rec[2 + i]);
		smp_rmb();		/* the copy before the check */
		again = READ_ONCE(h->in_seq);
		if (again != seq) {
			seq = again;	/* the daemon moved on: the other record */
			continue;
		}
		memcpy(u->in_vals, u->in_next, u->nin * sizeof(u32));
		u->in_tag = tag;
		u->in_seq = seq;
		u->fresh = now;
		WRITE_ONCE(h->in_taken, seq);
		if (u->status & IEC_USER_STALE) {
			u->status &= ~IEC_USER_STALE;
			WRITE_ONCE(h->status, u->status);
		}
		break;
	}
	if (u->stale_ms && ktime_ms_delta(now, u->fresh) > u->stale_ms) {
		u->status |= IEC_USER_STALE;
		WRITE_ONCE(h->status, u->status);
		*why = "inputs stale";
		return -ETIMEDOUT;
	}
	if (u->publish_in)	/* no outputs to wait for: the cycle begins */
		iec_user_publish(u, t, 0);
	return 0;
}

/* After copy-out (or a safe state): the outputs to the daemon. */
static void iec_user_cycle_out(struct iec_io_dev *d, struct iec_task *t,
			       bool safe)
{
	iec_user_publish(d->handle, t, safe ? IEC_USER_SAFE : 0);
}

static const struct iec_io_provider iec_io_user = {
	.name = "user",
	.open = iec_user_open,
	.close = iec_user_close,
	.check = iec_user_check,
	.read = iec_user_read,
	.write = iec_user_write,
	.cycle_in = iec_user_cycle_in,
	.cycle_out = iec_user_cycle_out,
	.expose = iec_user_expose,
	.withdraw = iec_user_withdraw,
};
