// SPDX-License-Identifier: GPL-2.0-only OR MIT
/*
 * iec_io_comedi.c - the comedi provider of iec_io.c: a device is
 * /dev/comedi<minor>, opened with kcomedilib's comedi_open() (the
 * reference keeps the comedi_device until module exit).
 *
 * Digital channels use kcomedilib's comedi_dio_bitfield2(); a DIO channel
 * is configured as an input or an output at load (comedi_dio_config()).
 * Linux 6.1's kcomedilib exports no analog call (comedi_data_read/write
 * are comedilib's, in user space), so an analog sample is one INSN_READ or
 * INSN_WRITE instruction given to the subdevice the way kcomedilib gives
 * its own (comedi_do_insn() in drivers/comedi/kcomedilib/kcomedilib_main.c):
 * under the device's mutex, on an attached device, a subdevice not busy
 * with an asynchronous command; chanspec = CR_PACK(channel, range,
 * AREF_GROUND).  Every call may sleep (the mutex): iec_io.c calls them
 * from the task thread with no lock held.  A device detached meanwhile
 * (its driver removed) answers -ENODEV, which faults the task.
 *
 * Interrupts: comedi_parport's ACK line.  kcomedilib has no call for
 * comedi's asynchronous commands (the driver's own way to report the
 * interrupt, through its subdevice 3), so the driver is attached without
 * an IRQ and this provider requests the line itself: the primary handler
 * checks the control register's interrupt enable (a shared line's other
 * interrupts are not ours), reads the status register (which acknowledges
 * the interrupt of QEMU's emulated port; harmless on a real one) and
 * wakes the threaded handler.  The enable bit is set and cleared under the
 * device's mutex, as comedi_parport's control-line writes (which keep it)
 * are.
 */
#include <linux/comedi/comedidev.h>
#include <linux/comedi/comedilib.h>
#include <linux/io.h>
#include <linux/mutex.h>
#include <linux/rwsem.h>

static int iec_comedi_open(struct iec_io_dev *d, const char **why)
{
	char path[24];
	struct comedi_device *dev;

	snprintf(path, sizeof(path), "/dev/comedi%u", d->minor);
	dev = comedi_open(path);
	if (!dev) {
		*why = "no attached comedi device at that minor (is its driver loaded?)";
		return -ENODEV;
	}
	d->handle = dev;
	return 0;
}

static void iec_comedi_close(struct iec_io_dev *d)
{
	if (d->handle)
		comedi_close(d->handle);
	d->handle = NULL;
}

static const int iec_comedi_types[] = {
	[IEC_IO_AI] = COMEDI_SUBD_AI,
	[IEC_IO_AO] = COMEDI_SUBD_AO,
	[IEC_IO_DI] = COMEDI_SUBD_DI,
	[IEC_IO_DO] = COMEDI_SUBD_DO,
	[IEC_IO_DIO] = COMEDI_SUBD_DIO,
};

static int iec_comedi_check(struct iec_io_dev *d, const struct iec_io_bind *b,
			    const char **why)
{
	struct comedi_device *dev = d->handle;
	struct comedi_subdevice *s;
	unsigned int maxdata;
	int ret = 0;

	down_read(&dev->attach_lock);
	if (!dev->attached) {
		*why = "the device is not attached";
		ret = -ENODEV;
	} else if (b->subdev >= dev->n_subdevices) {
		*why = "no such subdevice";
		ret = -ENODEV;
	} else {
		s = &dev->subdevices[b->subdev];
		maxdata = s->maxdata_list ? s->maxdata_list[min_t(int, b->chan, s->n_chan - 1)] :
			  s->maxdata;
		if (s->type != iec_comedi_types[b->kind]) {
			*why = "the subdevice is of another kind than the I/O map says";
			ret = -ENODEV;
		} else if (b->chan >= s->n_chan) {
			*why = "the subdevice has fewer channels than the I/O map says";
			ret = -ENODEV;
		} else if (b->kind <= IEC_IO_AO && maxdata != b->maxdata) {
			*why = "the channel's resolution differs from the I/O map's";
			ret = -ENODEV;
		} else if (b->kind <= IEC_IO_AO &&
			   (s->range_table_list || s->range_table) &&
			   b->range >= (s->range_table_list ?
					s->range_table_list[b->chan]->length :
					s->range_table->length)) {
			*why = "the channel has no such range";
			ret = -ENODEV;
		}
	}
	up_read(&dev->attach_lock);
	if (!ret && b->kind == IEC_IO_DIO) {
		ret = comedi_dio_config(dev, b->subdev, b->chan,
					b->input ? COMEDI_INPUT : COMEDI_OUTPUT);
		if (ret < 0)
			*why = "the line cannot be configured as the I/O map's direction";
		else
			ret = 0;
	}
	return ret;
}

/* One INSN_READ or INSN_WRITE of one sample, as kcomedilib does its own. */
static int iec_comedi_insn(struct comedi_device *dev,
			   const struct iec_io_bind *b, bool write, u32 *data)
{
	struct comedi_insn insn = {
		.insn = write ? INSN_WRITE : INSN_READ,
		.n = 1,
		.subdev = b->subdev,
		.chanspec = CR_PACK(b->chan, b->range, AREF_GROUND),
	};
	struct comedi_subdevice *s;
	unsigned int sample = *data;
	int ret;

	mutex_lock(&dev->mutex);
	if (!dev->attached) {
		ret = -ENODEV;
		goto out;
	}
	if (b->subdev >= dev->n_subdevices) {
		ret = -EINVAL;
		goto out;
	}
	s = &dev->subdevices[b->subdev];
	if (s->busy) {
		ret = -EBUSY;
		goto out;
	}
	if (write)
		ret = s->insn_write ? s->insn_write(dev, s, &insn, &sample) : -EIO;
	else
		ret = s->insn_read ? s->insn_read(dev, s, &insn, &sample) : -EIO;
	if (ret >= 0)
		ret = ret == 1 ? 0 : -EIO;
	if (!ret)
		*data = sample;
out:
	mutex_unlock(&dev->mutex);
	return ret;
}

static int iec_comedi_read(struct iec_io_dev *d, const struct iec_io_bind *b,
			   u32 *raw)
{
	unsigned int bits = 0;
	int ret;

	if (b->kind == IEC_IO_AI)
		return iec_comedi_insn(d->handle, b, false, raw);
	ret = comedi_dio_bitfield2(d->handle, b->subdev, 0, &bits,
				   b->chan & ~31U);
	if (ret < 0)
		return ret;
	*raw = (bits >> (b->chan & 31)) & 1;
	return 0;
}

static int iec_comedi_write(struct iec_io_dev *d, const struct iec_io_bind *b,
			    u32 raw)
{
	unsigned int bits = raw ? 1U << (b->chan & 31) : 0;
	int ret;

	if (b->kind == IEC_IO_AO)
		return iec_comedi_insn(d->handle, b, true, &raw);
	ret = comedi_dio_bitfield2(d->handle, b->subdev, 1U << (b->chan & 31),
				   &bits, b->chan & ~31U);
	return ret < 0 ? ret : 0;
}

#define IEC_PARPORT_STATUS	1
#define IEC_PARPORT_CTRL	2
#define IEC_PARPORT_IRQ_ENA	0x10

/* Hard interrupt context (IRQF_ONESHOT: not forced into a thread). */
static irqreturn_t iec_parport_irq(int irq, void *arg)
{
	struct iec_io_irq *q = arg;

	if (!(inb(q->base + IEC_PARPORT_CTRL) & IEC_PARPORT_IRQ_ENA))
		return IRQ_NONE;
	inb(q->base + IEC_PARPORT_STATUS);
	WRITE_ONCE(q->stamp, ktime_get());
	return IRQ_WAKE_THREAD;
}

/* Sets or clears the interrupt enable under the device's mutex. */
static int iec_parport_enable(struct comedi_device *dev, bool on)
{
	unsigned int ctrl;
	int ret = 0;

	mutex_lock(&dev->mutex);
	if (dev->attached) {
		ctrl = inb(dev->iobase + IEC_PARPORT_CTRL);
		ctrl = on ? ctrl | IEC_PARPORT_IRQ_ENA : ctrl & ~IEC_PARPORT_IRQ_ENA;
		/* a stale pending interrupt (QEMU keeps its line up) goes */
		inb(dev->iobase + IEC_PARPORT_STATUS);
		outb(ctrl, dev->iobase + IEC_PARPORT_CTRL);
		inb(dev->iobase + IEC_PARPORT_STATUS);
	} else {
		ret = -ENODEV;
	}
	mutex_unlock(&dev->mutex);
	return ret;
}

static int iec_comedi_irq_on(struct iec_io_dev *d, struct iec_io_irq *q,
			     const char **why)
{
	struct comedi_device *dev = d->handle;
	int ret = 0;

	down_read(&dev->attach_lock);
	if (!dev->attached) {
		*why = "the device is not attached";
		ret = -ENODEV;
	} else if (strcmp(dev->driver->driver_name, "comedi_parport")) {
		*why = "ACK is an interrupt of comedi_parport; the device has another driver";
		ret = -ENODEV;
	} else if (dev->irq) {
		*why = "comedi_parport was attached with an IRQ and holds it: attach it with its I/O base only";
		ret = -EBUSY;
	} else {
		q->base = dev->iobase;
	}
	up_read(&dev->attach_lock);
	if (ret)
		return ret;
	ret = request_threaded_irq(q->line, iec_parport_irq, iec_io_irq_thread,
				   IRQF_ONESHOT, "iec2kmod", q);
	if (ret) {
		*why = "the IRQ line cannot be requested (held by another driver?)";
		return ret;
	}
	ret = iec_parport_enable(dev, true);
	if (ret) {
		free_irq(q->line, q);
		*why = "the device is not attached";
	}
	return ret;
}

static void iec_comedi_irq_off(struct iec_io_dev *d, struct iec_io_irq *q)
{
	iec_parport_enable(d->handle, false);
	free_irq(q->line, q);
}

static const struct iec_io_provider iec_io_comedi = {
	.name = "comedi",
	.open = iec_comedi_open,
	.close = iec_comedi_close,
	.check = iec_comedi_check,
	.read = iec_comedi_read,
	.write = iec_comedi_write,
	.irq_on = iec_comedi_irq_on,
	.irq_off = iec_comedi_irq_off,
};
